from rest_framework import serializers

from reports.figures.tiles import MAX_ZOOM
from reports.models import Report
from reports.services.rendering import MAX_TIMELINE_HOURS


class ReportSerializer(serializers.ModelSerializer):
    download = serializers.SerializerMethodField()

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
        )
        read_only_fields = fields

    def get_download(self, report) -> str | None:
        if report.status != Report.Status.DONE or not report.pdf:
            return None
        request = self.context.get("request")
        url = f"/api/reports/{report.pk}/pdf/"
        return request.build_absolute_uri(url) if request else url


class ReportRequestSerializer(serializers.Serializer):
    test_event = serializers.IntegerField()
    options = serializers.DictField(required=False, default=dict)


def _lines(label: str) -> serializers.CharField:
    return serializers.CharField(
        label=label,
        required=False,
        allow_blank=True,
        style={"base_template": "textarea.html"},
        help_text="One line each.",
    )


class ReportFormSerializer(serializers.Serializer):
    """The report dialog's fields, as the GUI shows them (gui/forms.py).  What is
    sent is checked by the report service (``generation.REQUESTABLE`` and
    ``ReportOptions.problems``), not here."""

    name = serializers.CharField(label="Report name", required=False, allow_blank=True)
    version = serializers.CharField(label="Report version", required=False, initial="1.0")
    recipient = serializers.CharField(label="Recipient", required=False, allow_blank=True)
    recipient_address = _lines("Recipient address")
    creator = serializers.CharField(label="Creator", required=False, allow_blank=True)
    creator_address = _lines("Creator address")
    local = serializers.ChoiceField(
        label="Positions",
        choices=[("false", "GPS"), ("true", "Local (map frame)")],
        initial="false",
    )
    min_timeline_hours = serializers.FloatField(
        label="Timeline at least (hours, optional)",
        required=False,
        help_text=f"0 to {MAX_TIMELINE_HOURS}; the timelines of several reports then compare.",
    )
    max_zoom = serializers.IntegerField(
        label=f"Closest map zoom (1–{MAX_ZOOM}, optional)", required=False
    )
