"""Admin pages of logins: a person's account with role and name on one page, and
robot accounts with the vehicles they log for (events/admin/ loads it)."""

from django import forms
from django.contrib import admin
from django.contrib.auth import get_user_model
from django.contrib.auth.admin import UserAdmin
from django.contrib.auth.forms import AdminUserCreationForm
from django.contrib.auth.models import Group
from django.utils.translation import gettext_lazy as _

from common import roles
from events.models import Personnel, RobotAccount
from events.services import configuration


@admin.register(RobotAccount)
class RobotAccountAdmin(admin.ModelAdmin):
    """The login of a robot in the robot group and the vehicles it may log for;
    ``manage.py ftt_robot_account`` makes one with a token in one step."""

    list_display = ["user", "bound_vehicles", "in_robot_group"]
    search_fields = ["user__username", "vehicles__key"]
    autocomplete_fields = ["user"]
    filter_horizontal = ["vehicles"]

    def get_queryset(self, request):
        queryset = super().get_queryset(request).select_related("user")
        return queryset.prefetch_related("vehicles", "user__groups")

    @admin.display(description=_("vehicles"))
    def bound_vehicles(self, obj):
        return ", ".join(v.key for v in obj.vehicles.all()) or "— (writes nothing)"

    @admin.display(description=_("in robot group"), boolean=True)
    def in_robot_group(self, obj):
        # Without the group the binding does nothing: the login keeps its people's role.
        return any(group.name == roles.ROBOT for group in obj.user.groups.all())


class RobotAccountInline(admin.StackedInline):
    """On a user's page: the vehicles this login may log for as a robot."""

    model = RobotAccount
    can_delete = True
    filter_horizontal = ["vehicles"]
    verbose_name = _("robot account (vehicles it logs for)")
    # Folded: most logins are people's; a robot's is made with ftt_robot_account.
    classes = ["collapse"]


User = get_user_model()
admin.site.unregister(User)


class PersonCreationForm(AdminUserCreationForm):
    """A person's login, role and name on one page (the name signs their notes)."""

    role = forms.ChoiceField(
        label=_("Role"),
        choices=[("", _("— none yet —"))] + [(role, _(role.title())) for role in roles.ORDER],
        required=False,
        help_text=_("Administrators also get into this configuration site."),
    )
    person_name = forms.CharField(
        label=_("Person's name"),
        max_length=200,
        required=False,
        help_text=_("Signs the notes this login writes; leave empty for no person record."),
    )
    institution = forms.CharField(label=_("Institution"), max_length=200, required=False)

    def save(self, commit=True):
        user = super().save(commit=False)
        user.is_staff = self.cleaned_data["role"] == roles.ADMINISTRATOR
        if commit:
            user.save()
            self.save_person(user)
        return user

    def save_person(self, user):
        if self.cleaned_data["role"]:
            user.groups.add(Group.objects.get(name=self.cleaned_data["role"]))
        if self.cleaned_data["person_name"]:
            configuration.create_configuration(
                Personnel,
                name=self.cleaned_data["person_name"],
                institution=self.cleaned_data["institution"],
                user=user,
            )


@admin.register(User)
class FttUserAdmin(UserAdmin):
    add_form = PersonCreationForm
    add_fieldsets = (
        *UserAdmin.add_fieldsets,
        (_("Role and person"), {"fields": ("role", "person_name", "institution")}),
    )
    inlines = [*UserAdmin.inlines, RobotAccountInline]

    def get_inlines(self, request, obj):
        # A new login is a person's; a robot's block appears once it exists.
        return self.inlines if obj is not None else []

    def save_model(self, request, obj, form, change):
        super().save_model(request, obj, form, change)
        if not change:
            form.save_person(obj)
