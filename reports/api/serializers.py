from rest_framework import serializers

from reports.models import Report
from reports.services.generation import COMPARE


class ReportSerializer(serializers.ModelSerializer):
    download = serializers.SerializerMethodField()
    kind = serializers.SerializerMethodField()
    compare = serializers.SerializerMethodField()

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
        )
        read_only_fields = fields

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
    """Either one test event, or ``compare``: the ids of two or more to compare."""

    test_event = serializers.IntegerField(required=False)
    compare = serializers.ListField(
        child=serializers.IntegerField(), required=False, min_length=2, max_length=50
    )
    options = serializers.DictField(required=False, default=dict)

    def validate(self, attrs):
        if ("test_event" in attrs) == ("compare" in attrs):
            raise serializers.ValidationError(
                {"test_event": ["Give either test_event or compare (two or more ids)."]}
            )
        return attrs
