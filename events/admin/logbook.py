"""Admin pages of the logbook: test events, shifts, legs, segments and notes,
browsable up and down; closing and re-opening are actions through the services."""

from django.contrib import admin
from django.core.exceptions import PermissionDenied, ValidationError
from django.utils.translation import gettext_lazy as _
from leaflet.admin import LeafletGeoAdminMixin

from events.admin.shared import (
    ENTRY_STAMPS,
    HistoryAdmin,
    ServiceDeleteMixin,
    admin_link,
    run_service,
)
from events.models import (
    Leg,
    Note,
    Segment,
    Shift,
    TestEvent,
)
from events.selectors import labels
from events.services import finality, logs, notes, segments


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
