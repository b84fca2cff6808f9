"""Django admin: the configuration UI for test administrators.

Configuration and catalogues are edited here.  The log hierarchy is browsable
with links up and down; its state changes (close, re-open) are admin actions
that call the service layer, and robot-recorded data is read-only.
"""

from django import forms
from django.contrib import admin, messages
from django.core.exceptions import PermissionDenied, ValidationError
from django.urls import reverse
from django.utils.html import format_html
from django.utils.translation import gettext_lazy as _
from leaflet.admin import LeafletGeoAdminMixin
from simple_history.admin import SimpleHistoryAdmin

from common import roles
from events.history import authored
from events.models import (
    ItoReason,
    Leg,
    Note,
    Performer,
    Personnel,
    PoseSource,
    RobotAccount,
    Segment,
    SegmentType,
    Shift,
    TestEvent,
    Vehicle,
    Weather,
)
from events.selectors import labels
from events.services import configuration, deletion, finality, logs, notes, segments

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


# --- configuration ----------------------------------------------------------------------------


@admin.register(Personnel)
class PersonnelAdmin(ServiceDeleteMixin, HistoryAdmin):
    list_display = ["name", "institution", "user"]
    search_fields = ["name", "institution", "user__username"]
    list_filter = ["institution"]
    autocomplete_fields = ["user"]


@admin.register(Performer)
class PerformerAdmin(ServiceDeleteMixin, admin.ModelAdmin):
    list_display = ["institution"]
    search_fields = ["institution"]


class RobotBindingInline(admin.TabularInline):
    """On a vehicle's page: the robot accounts whose tokens log into its legs."""

    model = RobotAccount.vehicles.through
    extra = 0
    autocomplete_fields = ["robotaccount"]
    verbose_name = _("robot account")
    verbose_name_plural = _(
        "robot accounts logging for this vehicle (their tokens write here only)"
    )


@admin.register(Vehicle)
class VehicleAdmin(ServiceDeleteMixin, HistoryAdmin):
    list_display = ["key", "short_description", "institution"]
    search_fields = ["key", "short_description", "long_description", "institution"]
    list_filter = ["institution"]
    inlines = [RobotBindingInline]


@admin.register(PoseSource)
class PoseSourceAdmin(ServiceDeleteMixin, admin.ModelAdmin):
    list_display = ["key", "short_description"]
    search_fields = ["key", "short_description", "long_description"]


# --- catalogues -------------------------------------------------------------------------------


class CatalogueAdmin(ServiceDeleteMixin, admin.ModelAdmin):
    """Everyone with admin access may look; only administrators change."""

    search_fields = ["key", "short_description", "long_description"]
    # Refuses the keys the logging rules name (unassigned, ito, auto, unknown).
    delete_service = staticmethod(configuration.delete_configuration)

    def _may_write(self, request):
        return roles.may_write(request.user, self.model)

    def has_add_permission(self, request):
        return self._may_write(request)

    def has_change_permission(self, request, obj=None):
        return self._may_write(request)

    def has_delete_permission(self, request, obj=None):
        if obj is not None and configuration.is_used_by_rules(obj):
            return False
        return self._may_write(request)

    def has_view_permission(self, request, obj=None):
        return roles.has_role(request.user, roles.VIEWER)

    def get_readonly_fields(self, request, obj=None):
        return ["key"] if obj is not None else []


def colour_swatch(obj):
    return format_html(
        '<span style="display:inline-block;width:1.5em;height:1em;background:rgb({})"></span> {}',
        obj.color,
        obj.color,
    )


colour_swatch.short_description = _("colour")


@admin.register(Weather)
class WeatherAdmin(CatalogueAdmin):
    list_display = ["key", "short_description", "long_description"]


@admin.register(ItoReason)
class ItoReasonAdmin(CatalogueAdmin, HistoryAdmin):
    list_display = ["key", "short_description", colour_swatch, "counts_as_intervention", "quick"]
    list_filter = ["counts_as_intervention", "quick"]


@admin.register(SegmentType)
class SegmentTypeAdmin(CatalogueAdmin):
    list_display = ["key", "short_description", colour_swatch]

    def has_add_permission(self, request):
        # The state machine knows ITO, AUTO and UNKNOWN only; another type could never be logged.
        return False


# --- the log hierarchy ------------------------------------------------------------------------


class ReadOnlyInline(admin.TabularInline):
    extra = 0
    can_delete = False
    show_change_link = True

    def has_add_permission(self, request, obj=None):
        return False

    def has_change_permission(self, request, obj=None):
        return False

    def get_readonly_fields(self, request, obj=None):
        # Saving the parent page builds the inline's form too; listing the
        # fields as read-only keeps non-editable ones (number) out of that form.
        return self.fields


class ShiftInline(ReadOnlyInline):
    model = Shift
    fields = ["number", "vehicle", "performer", "start", "end"]


class LegInline(ReadOnlyInline):
    model = Leg
    fields = ["number", "weather", "default_pose_source", "start", "end"]


class SegmentInline(ReadOnlyInline):
    model = Segment
    fk_name = "leg"
    fields = ["segment_type", "parent", "ito_reason", "start", "end"]

    def get_queryset(self, request):
        return super().get_queryset(request).select_related("segment_type", "ito_reason", "parent")


class ChildInline(SegmentInline):
    fk_name = "parent"


class NoteInline(ReadOnlyInline):
    # Edited on the note's own page, where saving goes through the notes service.
    model = Note
    fields = ["author", "text", "created", "edited"]


@admin.register(TestEvent)
class TestEventAdmin(ServiceDeleteMixin, HistoryAdmin):
    list_display = ["__str__", "location", "version", "time_zone", "start", "end", "finalised"]
    list_filter = ["time_zone", ("end", admin.EmptyFieldListFilter)]
    search_fields = ["location", "version", "note"]
    date_hierarchy = "start"
    readonly_fields = [*ENTRY_STAMPS, "finalised", "finalised_by"]
    fields = ["location", "version", "time_zone", "language", "note", *readonly_fields]
    inlines = [ShiftInline]
    actions = ["close_selected", "reopen_selected", "finalise_selected"]

    def save_model(self, request, obj, form, change):
        values = {name: form.cleaned_data[name] for name in logs.TEST_EVENT_FIELDS}
        if change:
            logs.update_test_event(obj, **values)
        else:
            obj.pk = logs.create_test_event(**values).pk

    @admin.action(description=_("End selected test events (and everything open below)"))
    def close_selected(self, request, queryset):
        run_service(self, request, queryset, logs.close_test_event, "test events ended")

    @admin.action(description=_("Re-open selected test events"))
    def reopen_selected(self, request, queryset):
        run_service(self, request, queryset, logs.reopen_test_event, "test events re-opened")

    @admin.action(description=_("Finalise selected closed test events (freezes their taxonomy)"))
    def finalise_selected(self, request, queryset):
        def finalise(event):
            try:
                return finality.finalise_test_event(event, by=request.user)
            except PermissionDenied as exc:
                raise ValidationError(str(exc)) from None

        run_service(self, request, queryset, finalise, "test events finalised")


@admin.register(Shift)
class ShiftAdmin(ServiceDeleteMixin, HistoryAdmin):
    list_display = ["__str__", "test_event_link", "vehicle", "performer", "start", "end"]
    list_filter = ["vehicle", "performer", ("end", admin.EmptyFieldListFilter)]
    search_fields = ["test_intent", "workspace", "note", "test_event__location"]
    list_select_related = ["test_event", "vehicle", "performer"]
    readonly_fields = ["test_event_link", "number", *ENTRY_STAMPS]
    inlines = [LegInline]
    actions = ["close_selected"]

    def get_fields(self, request, obj=None):
        head = ["test_event_link", "number"] if obj else ["test_event"]
        return [*head, *logs.SHIFT_FIELDS, *ENTRY_STAMPS]

    def get_readonly_fields(self, request, obj=None):
        return self.readonly_fields if obj else ENTRY_STAMPS

    @admin.display(description=_("test event"))
    def test_event_link(self, obj):
        return admin_link(obj.test_event)

    def save_model(self, request, obj, form, change):
        values = {name: form.cleaned_data[name] for name in logs.SHIFT_FIELDS}
        if change:
            logs.update_shift(obj, **values)
        else:
            vehicle = values.pop("vehicle")
            created = logs.create_shift(
                test_event=form.cleaned_data["test_event"], vehicle=vehicle, **values
            )
            obj.pk = created.pk

    @admin.action(description=_("End selected shifts (and everything open below)"))
    def close_selected(self, request, queryset):
        run_service(self, request, queryset, logs.close_shift, "shifts ended")


@admin.register(Leg)
class LegAdmin(ServiceDeleteMixin, HistoryAdmin):
    list_display = ["__str__", "shift_link", "weather", "default_pose_source", "start", "end"]
    list_filter = ["weather", ("end", admin.EmptyFieldListFilter)]
    search_fields = ["note", "recording"]
    list_select_related = ["shift", "weather", "default_pose_source"]
    readonly_fields = ["shift_link", "number", *ENTRY_STAMPS]
    inlines = [SegmentInline]
    actions = ["close_selected"]

    def get_fields(self, request, obj=None):
        head = ["shift_link", "number"] if obj else ["shift"]
        return [*head, *logs.LEG_FIELDS, *ENTRY_STAMPS]

    def get_readonly_fields(self, request, obj=None):
        return self.readonly_fields if obj else ENTRY_STAMPS

    @admin.display(description=_("shift"))
    def shift_link(self, obj):
        return admin_link(obj.shift, f"{obj.shift} of {obj.shift.test_event}")

    def get_inline_instances(self, request, obj=None):
        return super().get_inline_instances(request, obj) if obj else []

    def save_model(self, request, obj, form, change):
        values = {name: form.cleaned_data[name] for name in logs.LEG_FIELDS}
        if change:
            logs.update_leg(obj, **values)
        else:
            obj.pk = logs.create_leg(shift=form.cleaned_data["shift"], **values).pk

    @admin.action(description=_("End selected legs (and their open segments)"))
    def close_selected(self, request, queryset):
        run_service(self, request, queryset, logs.close_leg, "legs ended")


@admin.register(Segment)
class SegmentAdmin(ServiceDeleteMixin, LeafletGeoAdminMixin, HistoryAdmin):
    list_display = ["number", "leg_link", "segment_type", "ito_reason", "start", "end"]
    list_filter = ["segment_type", "ito_reason", ("parent", admin.EmptyFieldListFilter)]
    search_fields = ["obstacle", "lighting", "slope"]
    list_select_related = ["leg__shift__test_event", "segment_type", "ito_reason"]
    fields = [
        "leg_link",
        "parent_link",
        "segment_type",
        *Segment.ANNOTATION_FIELDS,
        "start_position",
        "start_local_x",
        "start_local_y",
        "start_local_frame",
        "start",
        "end",
        "robot_stamp",
        "uid",
        "modified",
        "annotated",
    ]
    inlines = [ChildInline, NoteInline]
    actions = ["close_selected"]

    def has_add_permission(self, request):
        # Segments come from mode switches (robot or GUI), never from a blank form.
        return False

    def get_readonly_fields(self, request, obj=None):
        editable = set(Segment.ANNOTATION_FIELDS) if obj and obj.parent_id else set()
        return [f for f in self.fields if f not in editable]

    def get_changelist_instance(self, request):
        # The GUI's numbers ("#7.1"), for the whole page in one query.
        changelist = super().get_changelist_instance(request)
        rows = list(changelist.result_list)
        numbers = labels.legs_numbers({row.leg_id for row in rows})
        for row in rows:
            leg_number, number = numbers[row.pk]
            row.label = labels.label(leg_number, number)
        return changelist

    @admin.display(description=_("segment"))
    def number(self, obj):
        kind = _("reason") if obj.parent_id else _("run")
        return f"{obj} {obj.segment_type_id.upper()} {kind}"

    def get_object(self, request, object_id, from_field=None):
        segment = super().get_object(request, object_id, from_field)
        if segment is not None:
            segment.label = labels.segment_label(segment)
        return segment

    @admin.display(description=_("leg"))
    def leg_link(self, obj):
        return admin_link(obj.leg, f"{obj.leg} of {obj.leg.shift}")

    @admin.display(description=_("master"))
    def parent_link(self, obj):
        return admin_link(obj.parent, obj.parent and labels.segment_label(obj.parent))

    def save_model(self, request, obj, form, change):
        values = {n: form.cleaned_data[n] for n in form.changed_data if n != "change_reason"}
        if values:
            segments.annotate_segment(obj, **values)

    @admin.action(description=_("End selected segments"))
    def close_selected(self, request, queryset):
        run_service(self, request, queryset, segments.close_segment, "segments ended")


@admin.register(Note)
class NoteAdmin(ServiceDeleteMixin, HistoryAdmin):
    list_display = ["__str__", "author", "segment", "created", "edited"]
    search_fields = ["text", "author__name"]
    list_select_related = ["author", "segment__segment_type"]
    readonly_fields = ["segment", "author", "created", "edited", "uid"]

    def has_add_permission(self, request):
        return False

    def has_change_permission(self, request, obj=None):
        allowed = super().has_change_permission(request, obj)
        return allowed and (obj is None or notes.may_change_note(request.user, obj))

    def has_delete_permission(self, request, obj=None):
        allowed = super().has_delete_permission(request, obj)
        return allowed and (obj is None or notes.may_change_note(request.user, obj))

    def delete_model(self, request, obj):
        notes.delete_note(obj, by=request.user)

    def save_model(self, request, obj, form, change):
        # The service stamps "edited" and tells the live map, as for API edits.
        notes.edit_note(obj, text=form.cleaned_data["text"], by=request.user)


from events import account_admin, test_plan_admin  # noqa: E402,F401  (register their pages)
