"""Query filters shared by the API list endpoints: by parent, time range, open/closed state
and bounding box."""

import json
import math
from datetime import UTC

import django_filters as filters
from django import forms
from django.db.models import Exists, OuterRef, Q
from django.http import QueryDict
from django.utils.translation import gettext as _
from django_filters.fields import IsoDateTimeField
from django_filters.rest_framework import DjangoFilterBackend
from rest_framework import serializers
from rest_framework_gis.filters import InBBoxFilter

from common.areas import AreaError, area_from_box, area_from_text
from events.models import Leg, Note, Segment, SegmentType, Shift, TestEvent

# Ids beyond this cannot exist; rejecting them early keeps huge numbers away from the database.
MAX_ID = 2**63 - 1


class IdFilter(filters.Filter):
    """An integer id; anything else is a 400 with a field message."""

    field_class = forms.IntegerField

    def __init__(self, *args, **kwargs):
        kwargs.setdefault("min_value", 1)
        kwargs.setdefault("max_value", MAX_ID)
        super().__init__(*args, **kwargs)


class StrictBooleanField(forms.NullBooleanField):
    """``true`` / ``false`` (or 1 / 0); anything else is an error rather than "no filter"."""

    def to_python(self, value):
        if value in (None, ""):
            return None
        if str(value).lower() in ("true", "1"):
            return True
        if str(value).lower() in ("false", "0"):
            return False
        raise forms.ValidationError(_("Use true or false."), code="invalid")

    def validate(self, value):
        pass


class BooleanFilter(filters.BooleanFilter):
    field_class = StrictBooleanField

    def __init__(self, *args, **kwargs):
        # A text widget hands the raw value to the field; the select widget would
        # quietly turn unknown values into "no filter".
        kwargs.setdefault("widget", forms.TextInput)
        super().__init__(*args, **kwargs)


class UtcDateTimeField(IsoDateTimeField):
    """ISO 8601 with any offset, compared in UTC: PostgreSQL refuses offsets beyond ±15:59."""

    def to_python(self, value):
        value = super().to_python(value)
        if value is None:
            return None
        try:
            return value.astimezone(UTC)
        except OverflowError:
            raise forms.ValidationError(_("Date/time out of range."), code="overflow") from None


class DateTimeFilter(filters.IsoDateTimeFilter):
    field_class = UtcDateTimeField


class TimeRangeFilterSet(filters.FilterSet):
    """Adds ``<field>_after`` / ``<field>_before`` for each name in ``Meta.time_fields``."""

    @classmethod
    def get_filters(cls):
        result = super().get_filters()
        for name in getattr(getattr(cls, "Meta", None), "time_fields", ()):
            result[f"{name}_after"] = DateTimeFilter(
                field_name=name, lookup_expr="gte", label=f"{name} at or after (ISO 8601)"
            )
            result[f"{name}_before"] = DateTimeFilter(
                field_name=name, lookup_expr="lt", label=f"{name} before (ISO 8601)"
            )
        return result


class OpenStateFilterSet(TimeRangeFilterSet):
    open = BooleanFilter(
        field_name="end", lookup_expr="isnull", label="true: still open; false: closed"
    )


class TestEventFilter(OpenStateFilterSet):
    class Meta:
        model = TestEvent
        fields = []
        time_fields = ["start", "end", "modified"]


class ShiftFilter(OpenStateFilterSet):
    test_event = IdFilter(field_name="test_event_id")
    vehicle = IdFilter(field_name="vehicle_id")

    class Meta:
        model = Shift
        fields = []
        time_fields = ["start", "end", "modified"]


class LegFilter(OpenStateFilterSet):
    shift = IdFilter(field_name="shift_id")
    test_event = IdFilter(field_name="shift__test_event_id")

    class Meta:
        model = Leg
        fields = []
        time_fields = ["start", "end", "modified"]


class AreaField(forms.CharField):
    """A GeoJSON or WKT polygon, cut at the antimeridian (common.areas)."""

    def to_python(self, value):
        value = super().to_python(value)
        if not value:
            return None
        try:
            return area_from_text(value)
        except AreaError as error:
            raise forms.ValidationError(str(error), code="invalid") from None


class AreaFilter(filters.Filter):
    """Rows whose point lies inside the area or on its edge."""

    field_class = AreaField

    def filter(self, qs, value):
        if value is None:
            return qs
        return qs.filter(**{f"{self.field_name}__intersects": value})


class SegmentFilter(OpenStateFilterSet):
    leg = IdFilter(field_name="leg_id")
    shift = IdFilter(field_name="leg__shift_id")
    test_event = IdFilter(field_name="leg__shift__test_event_id")
    parent = IdFilter(field_name="parent_id")
    master = BooleanFilter(
        field_name="parent", lookup_expr="isnull", label="true: masters only; false: children"
    )
    mode = filters.ChoiceFilter(
        field_name="segment_type_id",
        choices=[
            (SegmentType.ITO, "ITO"),
            (SegmentType.AUTO, "AUTO"),
            (SegmentType.UNKNOWN, "UNKNOWN"),
        ],
    )
    vehicle = IdFilter(field_name="leg__shift__vehicle_id")
    reason = filters.CharFilter(
        method="filter_reason", label="take-over reason key (of the reason, or of its take-over)"
    )
    version = filters.CharFilter(
        field_name="leg__shift__test_event__version", label="software version of the test event"
    )
    within = AreaFilter(
        field_name="start_position",
        label="where the segment started: a GeoJSON or WKT polygon (may cross ±180°)",
    )

    class Meta:
        model = Segment
        fields = []
        time_fields = ["start", "end", "robot_stamp", "modified"]

    def filter_reason(self, queryset, name, value):
        # Asked per segment the other filters leave (a child by the parent index),
        # not by collecting every segment with the reason first.
        child_with_reason = Segment.objects.filter(parent_id=OuterRef("pk"), ito_reason_id=value)
        return queryset.filter(Q(ito_reason_id=value) | Exists(child_with_reason))


class NoteFilter(TimeRangeFilterSet):
    segment = IdFilter(field_name="segment_id")
    leg = IdFilter(field_name="segment__leg_id")
    shift = IdFilter(field_name="segment__leg__shift_id")
    test_event = IdFilter(field_name="segment__leg__shift__test_event_id")
    author = IdFilter(field_name="author_id")

    class Meta:
        model = Note
        fields = []
        time_fields = ["created"]


def search_params(request, view):
    """A search's parameters: its query, or the body of a search sent by POST (an
    area of thousands of vertices does not fit in an address).  A JSON body names
    the same parameters; an area may be given there as a GeoJSON object."""
    searching = getattr(view, "action", None) in getattr(view, "read_actions", ())
    if request.method != "POST" or not searching:
        # Another POST's body is what it writes, never a filter.
        return request.query_params
    data = request.data
    if isinstance(data, QueryDict):
        # A form's token is the CSRF check's, not a parameter of the search.
        params = data.copy()
        params.pop("csrfmiddlewaretoken", None)
        return params
    if not isinstance(data, dict):
        raise serializers.ValidationError(
            {"non_field_errors": [_("Send the search's parameters as a JSON object.")]}
        )
    params = QueryDict(mutable=True)
    for name, value in data.items():
        if value is None:
            continue
        if isinstance(value, bool):
            value = "true" if value else "false"
        elif isinstance(value, dict | list):
            value = json.dumps(value)
        params[name] = str(value)
    return params


# What every list takes besides its filters: paging and DRF's format.
LIST_PARAMS = frozenset({"page", "page_size", "format"})


class SearchFilterBackend(DjangoFilterBackend):
    """The filter sets of the API's lists.  A parameter a list does not know is
    refused (400 naming it): a misspelt or missing filter would otherwise list
    every row.  A search sent by POST is read from its body (:func:`search_params`)."""

    def get_filterset_kwargs(self, request, queryset, view):
        return {
            **super().get_filterset_kwargs(request, queryset, view),
            "data": search_params(request, view),
        }

    def filter_queryset(self, request, queryset, view):
        listing = ("list", *getattr(view, "read_actions", ()))
        if getattr(view, "action", None) in listing:
            self._refuse_unknown(search_params(request, view), view, queryset)
        return super().filter_queryset(request, queryset, view)

    def _refuse_unknown(self, params, view, queryset) -> None:
        filterset_class = self.get_filterset_class(view, queryset)
        if filterset_class is None:
            return
        known = set(filterset_class.base_filters) | LIST_PARAMS
        known |= set(getattr(view, "extra_params", ()))
        if any(issubclass(backend, BBoxFilter) for backend in view.filter_backends):
            known.add(BBoxFilter.bbox_param)
        unknown = sorted(set(params) - known)
        if unknown:
            message = _("This list has no such filter; it takes: %(known)s.") % {
                "known": ", ".join(sorted(known))
            }
            raise serializers.ValidationError({name: [message] for name in unknown})


class BBoxFilter(InBBoxFilter):
    """``in_bbox=min_lon,min_lat,max_lon,max_lat`` with finite WGS84 degrees."""

    def get_filter_bbox(self, request, view=None):
        raw = search_params(request, view).get(self.bbox_param)
        if not raw:
            return None
        message = _("Give in_bbox as min_lon,min_lat,max_lon,max_lat in degrees.")
        try:
            values = [float(n) for n in raw.split(",")]
        except ValueError:
            raise serializers.ValidationError({self.bbox_param: [message]}) from None
        if len(values) != 4 or not all(math.isfinite(v) for v in values):
            raise serializers.ValidationError({self.bbox_param: [message]})
        try:
            # west > east: a box across the antimeridian.
            return area_from_box(*values)
        except AreaError as error:
            raise serializers.ValidationError({self.bbox_param: [f"{message} {error}"]}) from None

    def filter_queryset(self, request, queryset, view):
        # Points on the box's edge count, and a box cut at ±180° is two boxes:
        # the library's "contained" would test the bounding box of both.
        field = getattr(view, "bbox_filter_field", None)
        area = self.get_filter_bbox(request, view) if field else None
        if area is None:
            return queryset
        return queryset.filter(**{f"{field}__intersects": area})
