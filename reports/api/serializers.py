from rest_framework import serializers

from reports.models import Report


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
