"""What the admin pages of every app share: read-only stamps, links, deletes and
actions through the services, amendments with a reason, change history."""

from django import forms
from django.contrib import messages
from django.core.exceptions import PermissionDenied, ValidationError
from django.urls import reverse
from django.utils.html import format_html
from django.utils.translation import gettext_lazy as _
from simple_history.admin import SimpleHistoryAdmin

from events.history import authored
from events.services import deletion, finality

# Shown, never edited: the services and the importer set them.
ENTRY_STAMPS = ["uid", "start", "end", "modified"]


def admin_link(obj, label=None):
    if obj is None:
        return "—"
    url = reverse(f"admin:{obj._meta.app_label}_{obj._meta.model_name}_change", args=[obj.pk])
    return format_html('<a href="{}">{}</a>', url, label or str(obj))


class ServiceDeleteMixin:
    """Deletes go through the service, so refusals name where a row is used."""

    delete_service = staticmethod(deletion.delete)

    def delete_model(self, request, obj):
        try:
            self.delete_service(obj)
        except ValidationError as exc:
            self.message_user(request, " ".join(exc.messages), messages.ERROR)

    def delete_queryset(self, request, queryset):
        for obj in queryset:
            self.delete_model(request, obj)


def run_service(modeladmin, request, queryset, service, done):
    changed = 0
    for obj in queryset:
        try:
            service(obj)
            changed += 1
        except ValidationError as exc:
            modeladmin.message_user(request, f"{obj}: {' '.join(exc.messages)}", messages.WARNING)
    if changed:
        modeladmin.message_user(request, f"{changed} {done}.", messages.SUCCESS)


class AmendmentForm(forms.ModelForm):
    """A change of a row of a final test event needs a reason (events.services.finality);
    refused here as a form error rather than after saving."""

    change_reason = forms.CharField(
        required=False,
        label=_("Change reason"),
        widget=forms.Textarea(attrs={"rows": 2}),
        help_text=_("Why this is changed; required for a final test event."),
    )

    def clean(self):
        data = super().clean()
        row = self.instance
        if row.pk is None:
            # A row to be added is checked by the parent it names.
            model = self._meta.model
            parents = [f.name for f in model._meta.concrete_fields if f.many_to_one]
            row = model(**{name: data[name] for name in parents if data.get(name) is not None})
        try:
            with authored(reason=data.get("change_reason", "")):
                finality.require_amendable_row(row)
        except PermissionDenied as exc:
            raise ValidationError(str(exc)) from None
        except ValidationError as exc:
            raise ValidationError({"change_reason": exc.messages}) from None
        return data


class AmendmentAdmin:
    """A reason field on a row's form, needed for a final test event."""

    form = AmendmentForm

    def changeform_view(self, request, *args, **kwargs):
        # The reason reaches every history row the save writes (events.history).
        reason = request.POST.get("change_reason", "") if request.method == "POST" else ""
        with authored(reason=reason.strip()):
            return super().changeform_view(request, *args, **kwargs)

    def get_fields(self, request, obj=None):
        fields = list(super().get_fields(request, obj))
        if "change_reason" not in fields:
            fields.append("change_reason")
        return fields


class HistoryAdmin(AmendmentAdmin, SimpleHistoryAdmin):
    """Every tracked model: its history page, and a reason field when it is changed."""
