from django.conf import settings
from django.utils.functional import lazy
from django.utils.translation import gettext, gettext_noop
from django.utils.translation import gettext_lazy as _
from rest_framework import serializers

from events.models import Criterion, Leg
from reports.charts.tiles import MAX_ZOOM
from reports.documents.options import LEVELS, MAX_TIMELINE_HOURS, STANDARD
from reports.models import Report
from reports.selectors.content import scope_name
from reports.selectors.reports import expected_seconds
from reports.services.generation import COMPARE


class ReportSerializer(serializers.ModelSerializer):
    download = serializers.SerializerMethodField()
    kind = serializers.SerializerMethodField()
    compare = serializers.SerializerMethodField()
    scope = serializers.SerializerMethodField()
    expected_seconds = serializers.SerializerMethodField()
    # In the reader's language (common.deferred_text).
    message = serializers.CharField(source="shown_message", read_only=True)
    error = serializers.CharField(source="shown_error", read_only=True)

    class Meta:
        model = Report
        fields = (
            "id",
            "test_event",
            "status",
            "progress",
            "message",
            "options",
            "provisional",
            "created",
            "finished",
            "error",
            "download",
            "kind",
            "compare",
            "scope",
            "expected_seconds",
        )
        read_only_fields = fields

    def get_expected_seconds(self, report) -> float | None:
        """While it is made: how long reports like it took (median), else None."""
        if report.status not in (Report.Status.QUEUED, Report.Status.RUNNING):
            return None
        return expected_seconds(report, self.context.setdefault("expected_memo", {}))

    def get_scope(self, report) -> str:
        """What the report covers: "Test event", "Shift 2" or "Shift 2 · Leg 1"."""
        o = report.options
        return scope_name(shift=o.get("shift"), leg=o.get("leg"))

    def get_kind(self, report) -> str:
        return "comparison" if report.options.get(COMPARE) else "test_event"

    def get_compare(self, report) -> list[int]:
        """The compared test events (empty for a single event's report)."""
        return list(report.options.get(COMPARE) or [])

    def get_download(self, report) -> str | None:
        if report.status != Report.Status.DONE or not report.pdf:
            return None
        request = self.context.get("request")
        url = f"/api/reports/{report.pk}/pdf/"
        return request.build_absolute_uri(url) if request else url


class ReportRequestSerializer(serializers.Serializer):
    """Either one test event (or only its ``shift`` or ``leg``), or ``compare``:
    the ids of two or more to compare."""

    test_event = serializers.IntegerField(required=False)
    shift = serializers.IntegerField(required=False, allow_null=True)
    leg = serializers.IntegerField(required=False, allow_null=True)
    compare = serializers.ListField(
        child=serializers.IntegerField(), required=False, min_length=2, max_length=50
    )
    options = serializers.DictField(required=False, default=dict)

    def validate(self, attrs):
        if ("test_event" in attrs) == ("compare" in attrs):
            raise serializers.ValidationError(
                {"test_event": [_("Give either test_event or compare (two or more ids).")]}
            )
        if "compare" in attrs and (attrs.get("shift") or attrs.get("leg")):
            raise serializers.ValidationError(
                {"compare": [_("A comparison covers whole test events: leave out shift and leg.")]}
            )
        return attrs


def _filled(text: str, **values):
    """``text`` translated when shown (the dialog's language), then filled in."""
    return lazy(lambda: gettext(text) % values, str)()


def _lines(label: str) -> serializers.CharField:
    return serializers.CharField(
        label=label,
        required=False,
        allow_blank=True,
        style={"base_template": "textarea.html"},
        help_text=_("One line each."),
    )


class ReportFormSerializer(serializers.Serializer):
    """The report dialog's fields, as the GUI shows them (gui/forms.py).  What is
    sent is checked by the report service (``generation.REQUESTABLE`` and
    ``ReportOptions.problems``), not here."""

    name = serializers.CharField(label=_("Report name"), required=False, allow_blank=True)
    version = serializers.CharField(label=_("Report version"), required=False, initial="1.0")
    recipient = serializers.CharField(label=_("Recipient"), required=False, allow_blank=True)
    recipient_address = _lines(_("Recipient address"))
    creator = serializers.CharField(label=_("Creator"), required=False, allow_blank=True)
    creator_address = _lines(_("Creator address"))
    # Compact by default: the full level gives every segment a page (62 pages for
    # five minutes of driving in the field), which is seldom what is wanted first.
    level = serializers.ChoiceField(label=_("Detail"), choices=LEVELS, initial=STANDARD)
    image_appendix = serializers.ChoiceField(
        label=_("Camera images"),
        choices=[("false", _("Leave out")), ("true", _("Appendix with every image"))],
        initial="false",
    )
    local = serializers.ChoiceField(
        label=_("Positions"),
        choices=[("false", "GPS"), ("true", _("Local (map frame)"))],
        initial="false",
    )
    min_timeline_hours = serializers.FloatField(
        label=_("Timeline at least (hours, optional)"),
        required=False,
        help_text=_filled(
            gettext_noop("0 to %(max)s; the timelines of several reports then compare."),
            max=MAX_TIMELINE_HOURS,
        ),
    )
    max_zoom = serializers.IntegerField(
        label=_filled(gettext_noop("Closest map zoom (1–%(max)s, optional)"), max=MAX_ZOOM),
        required=False,
    )
    # Empty: the test event's own language (TestEvent.language).
    language = serializers.ChoiceField(
        label=_("Language"),
        choices=[("", _("The test event's language")), *settings.LANGUAGES],
        required=False,
        initial="",
    )


class JudgementSerializer(serializers.Serializer):
    criterion = serializers.PrimaryKeyRelatedField(queryset=Criterion.objects.all())
    leg = serializers.PrimaryKeyRelatedField(
        queryset=Leg.objects.all(), required=False, allow_null=True
    )
    passed = serializers.BooleanField()
    note = serializers.CharField(required=False, allow_blank=True, max_length=2000)
