"""Reports over the API: statistics as JSON, PDF jobs, exports.

Reading needs the viewer role; requesting a report needs operator.
"""

import json

from django.http import FileResponse, HttpResponse
from django.shortcuts import get_object_or_404
from django.utils.translation import gettext as _
from drf_spectacular.utils import OpenApiParameter, extend_schema
from rest_framework import status
from rest_framework.exceptions import ValidationError
from rest_framework.parsers import MultiPartParser
from rest_framework.response import Response
from rest_framework.views import APIView

from common import roles
from common.api.downloads import streamed_download
from common.api.permissions import RolePermission
from events.models import TestEvent
from events.services.plans import judge
from reports.api.serializers import (
    JudgementSerializer,
    ReportRequestSerializer,
    ReportSerializer,
)
from reports.documents.options import FULL, LEVELS
from reports.models import Report
from reports.selectors import exports
from reports.selectors.comparison import compare
from reports.selectors.disengagements import disengagements_csv, mileage_csv, reporting_year_of
from reports.selectors.plans import test_plan, test_plan_csv
from reports.selectors.provenance import amendments_of, verify_report
from reports.selectors.reports import reports_of
from reports.selectors.routes import (
    DEFAULT_THRESHOLD,
    RouteChoiceError,
    check_threshold,
    chosen_routes,
    compare_routes,
)
from reports.selectors.statistics import event_statistics
from reports.services.generation import (
    COMPARE,
    request_comparison,
    request_report,
)
from telemetry.storage.keys import TRACK_KINDS

MODE_PARAM = OpenApiParameter(
    "mode", str, enum=list(TRACK_KINDS), description="gps (default) or local"
)


def _mode(request) -> str:
    mode = request.query_params.get("mode", "gps")
    if mode not in TRACK_KINDS:
        message = _("mode must be one of %(modes)s.") % {"modes": ", ".join(TRACK_KINDS)}
        raise ValidationError({"mode": [message]})
    return mode


def _reporting_year(request, event) -> int:
    """``?year=`` (the DMV's reporting year), else the one the event starts in."""
    raw = request.query_params.get("year")
    if raw is None:
        return reporting_year_of(event.start.astimezone(event.tzinfo))
    if not raw.isdigit() or not 2 <= int(raw) <= 9999:
        raise ValidationError({"year": [_("Give the reporting year between 0002 and 9999.")]})
    return int(raw)


class StatisticsView(APIView):
    """Figures of a test event, per shift, leg and vehicle (seconds and metres)."""

    permission_classes = [RolePermission]
    read_role = roles.VIEWER

    @extend_schema(parameters=[MODE_PARAM], responses={200: dict})
    def get(self, request, test_event_id: int):
        event = get_object_or_404(TestEvent, pk=test_event_id)
        return Response(event_statistics(event, _mode(request)).as_dict())


class TestPlanView(APIView):
    """The test plan's verdicts: each test case, its criteria per case and per leg
    (pass, fail, not yet, needs a judgement), its progress, and the unplanned legs."""

    permission_classes = [RolePermission]
    read_role = roles.VIEWER

    @extend_schema(parameters=[MODE_PARAM], responses={200: dict})
    def get(self, request, test_event_id: int):
        event = get_object_or_404(TestEvent, pk=test_event_id)
        return Response(test_plan(event, _mode(request)).as_dict())


class JudgementView(APIView):
    """A person's verdict on a criterion judged by a person: {criterion, leg (optional,
    else the whole case), passed, note}."""

    permission_classes = [RolePermission]
    read_role = roles.VIEWER
    write_role = roles.OPERATOR

    @extend_schema(request=JudgementSerializer, responses={201: dict})
    def post(self, request):
        body = JudgementSerializer(data=request.data)
        body.is_valid(raise_exception=True)
        judgement = judge(**body.validated_data, by=request.user)
        return Response(
            {
                "criterion": judgement.criterion_id,
                "leg": judgement.leg_id,
                "passed": judgement.passed,
            },
            status=status.HTTP_201_CREATED,
        )


class ComparisonView(APIView):
    """Reliability of several test events side by side (?test_event=1&test_event=2)."""

    permission_classes = [RolePermission]
    read_role = roles.VIEWER

    @extend_schema(
        parameters=[OpenApiParameter("test_event", int, many=True), MODE_PARAM],
        responses={200: dict},
    )
    def get(self, request):
        ids = request.query_params.getlist("test_event")
        if len(ids) < 2 or not all(i.isdigit() for i in ids):
            raise ValidationError(
                {"test_event": [_("Give at least two test event ids (numbers).")]}
            )
        return Response(compare(_events([int(i) for i in ids], "test_event"), _mode(request)))


class RouteComparisonView(APIView):
    """Driven routes side by side (?leg=1&leg=2), or legs and a test case's planned
    route (?leg=1&case=3): per pair, each route's deviation from the other (metres:
    mean, 95th percentile, maximum, stretches beyond ``threshold``) and the
    discrete Fréchet distance."""

    permission_classes = [RolePermission]
    read_role = roles.VIEWER

    @extend_schema(
        parameters=[
            OpenApiParameter("leg", int, many=True),
            OpenApiParameter("case", int, many=True, description="a test case's planned route"),
            OpenApiParameter("threshold", float, description="metres (default 5)"),
        ],
        responses={200: dict},
    )
    def get(self, request):
        try:
            threshold = float(request.query_params.get("threshold", DEFAULT_THRESHOLD))
        except ValueError:
            threshold = -1.0
        try:
            threshold = check_threshold(threshold)
            routes = chosen_routes(_ids(request, "leg"), _ids(request, "case"))
        except RouteChoiceError as error:
            raise ValidationError({error.field: [str(error)]}) from None
        try:
            return Response(compare_routes(routes, threshold))
        except ValueError as error:
            raise ValidationError({"leg": [str(error)]}) from None


def _ids(request, field: str) -> list[int]:
    ids = request.query_params.getlist(field)
    if not all(i.isdigit() for i in ids):
        raise ValidationError({field: [_("Give ids as numbers.")]})
    return [int(i) for i in ids]


def _events(ids: list[int], field: str) -> list[TestEvent]:
    events = list(TestEvent.objects.filter(pk__in=ids))
    missing = sorted(set(ids) - {e.pk for e in events})
    if missing:
        raise ValidationError({field: [_("No test event with id %(id)s.") % {"id": missing[0]}]})
    return events


class ReportChoicesView(APIView):
    """The choices of the report dialog, so the GUI offers exactly what the server accepts."""

    permission_classes = [RolePermission]
    read_role = roles.VIEWER

    @extend_schema(responses={200: dict})
    def get(self, request):
        return Response(
            {
                "level": {
                    "default": FULL,
                    "choices": [{"value": value, "label": text} for value, text in LEVELS],
                },
                "image_appendix": {"default": True},
            }
        )


class ReportListView(APIView):
    permission_classes = [RolePermission]
    read_role = roles.VIEWER
    write_role = roles.OPERATOR

    @extend_schema(
        parameters=[OpenApiParameter("test_event", int)],
        responses={200: ReportSerializer(many=True)},
    )
    def get(self, request):
        event_id = request.query_params.get("test_event")
        if event_id is not None and not event_id.isdigit():
            raise ValidationError({"test_event": [_("A test event id is a number.")]})
        rows = reports_of(int(event_id) if event_id else None)
        return Response(ReportSerializer(rows, many=True, context={"request": request}).data)

    @extend_schema(request=ReportRequestSerializer, responses={202: ReportSerializer})
    def post(self, request):
        body = ReportRequestSerializer(data=request.data)
        body.is_valid(raise_exception=True)
        options = body.validated_data["options"]
        if "compare" in body.validated_data:
            events = _events(body.validated_data["compare"], "compare")
            report = request_comparison(events, options, user=request.user)
        else:
            event = get_object_or_404(TestEvent, pk=body.validated_data["test_event"])
            report = request_report(
                event,
                options,
                user=request.user,
                shift=body.validated_data.get("shift"),
                leg=body.validated_data.get("leg"),
            )
        data = ReportSerializer(report, context={"request": request}).data
        return Response(data, status=status.HTTP_202_ACCEPTED)


class ReportDetailView(APIView):
    permission_classes = [RolePermission]
    read_role = roles.VIEWER

    @extend_schema(responses={200: ReportSerializer})
    def get(self, request, pk: int):
        report = get_object_or_404(Report, pk=pk)
        return Response(ReportSerializer(report, context={"request": request}).data)


class ReportPdfView(APIView):
    permission_classes = [RolePermission]
    read_role = roles.VIEWER

    @extend_schema(responses={(200, "application/pdf"): bytes})
    def get(self, request, pk: int):
        report = get_object_or_404(Report, pk=pk, status=Report.Status.DONE)
        compared = report.options.get(COMPARE)
        if compared:
            name = f"ftt-comparison-{'-'.join(map(str, compared))}-{report.pk}.pdf"
        else:
            name = f"ftt-report-test-event-{report.test_event_id}-{report.pk}.pdf"
        return FileResponse(report.pdf.open("rb"), as_attachment=True, filename=name)


def _verdict(content: bytes, field: str, *, kept: bool = False) -> Response:
    verdict = verify_report(content, kept=kept)
    if verdict is None:
        message = _(
            "This file carries no FTT data digest: give a PDF or JSON report FTT made "
            "(reports made before FTT stamped them cannot be checked)."
        )
        raise ValidationError({field: [message]})
    return Response(verdict.as_dict())


class VerifyUploadView(APIView):
    """Is a report (PDF or JSON, uploaded as ``file``) still true to the data?
    The answer of ``ftt_report --verify``: ok, and when not, which records changed
    since the report, when, by whom and through what."""

    permission_classes = [RolePermission]
    read_role = roles.VIEWER
    # Checking changes nothing: whoever may read reports may check one.
    write_role = roles.VIEWER
    parser_classes = [MultiPartParser]

    @extend_schema(
        request={
            "multipart/form-data": {
                "type": "object",
                "properties": {"file": {"type": "string", "format": "binary"}},
            }
        },
        responses={200: dict},
    )
    def post(self, request):
        upload = request.FILES.get("file")
        if upload is None:
            raise ValidationError({"file": [_("Choose a report file (PDF or JSON) to check.")]})
        return _verdict(upload.read(), "file")


class ReportVerifyView(APIView):
    """The same check for a report this installation made and keeps."""

    permission_classes = [RolePermission]
    read_role = roles.VIEWER

    @extend_schema(responses={200: dict})
    def get(self, request, pk: int):
        report = get_object_or_404(Report, pk=pk, status=Report.Status.DONE)
        with report.pdf.open("rb") as pdf:
            return _verdict(pdf.read(), "report", kept=True)


class AmendmentsView(APIView):
    """Whether a test event is final and the changes made to it since (the
    report's list of amendments): {final, finalised, count, amendments}."""

    permission_classes = [RolePermission]
    read_role = roles.VIEWER

    @extend_schema(responses={200: dict})
    def get(self, request, test_event_id: int):
        event = get_object_or_404(TestEvent, pk=test_event_id)
        amendments = amendments_of(event)
        return Response(
            {
                "final": event.finalised is not None,
                "finalised": event.finalised,
                "count": len(amendments),
                "amendments": amendments,
            }
        )


class ExportView(APIView):
    """segments.csv, tracks.geojson or tracks.gpx of a test event."""

    permission_classes = [RolePermission]
    read_role = roles.VIEWER
    formats = {
        "segments.csv": "text/csv; charset=utf-8",
        "tracks.geojson": "application/geo+json",
        "tracks.gpx": "application/gpx+xml",
        "test-plan.csv": "text/csv; charset=utf-8",
        "test-plan.json": "application/json",
        "disengagements.csv": "text/csv; charset=utf-8",
        "autonomous-mileage.csv": "text/csv; charset=utf-8",
    }

    @extend_schema(
        parameters=[
            MODE_PARAM,
            OpenApiParameter(
                "year", int, description="autonomous-mileage.csv: the DMV's reporting year"
            ),
        ],
        responses={(200, "text/csv"): bytes},
    )
    def get(self, request, test_event_id: int, filename: str):
        event = get_object_or_404(TestEvent, pk=test_event_id)
        name = f"test-event-{event.pk}-{filename}"
        content_type = self.formats[filename]
        # Those that grow with the segments and poses are streamed, the tables
        # of a few rows per test case or take-over are sent whole.
        if filename == "segments.csv":
            pieces = exports.segments_csv_rows(event, _mode(request))
            return streamed_download(request, pieces, content_type, name)
        if filename == "tracks.geojson":
            return streamed_download(
                request, exports.tracks_geojson_pieces(event), content_type, name
            )
        if filename == "tracks.gpx":
            return streamed_download(request, exports.tracks_gpx_pieces(event), content_type, name)
        if filename == "disengagements.csv":
            body = disengagements_csv([event])
        elif filename == "autonomous-mileage.csv":
            body = mileage_csv([event], _reporting_year(request, event))
        elif filename == "test-plan.csv":
            body = test_plan_csv(test_plan(event, _mode(request)))
        else:
            body = json.dumps(test_plan(event, _mode(request)).as_dict(), ensure_ascii=False)
        response = HttpResponse(body, content_type=content_type)
        response["Content-Disposition"] = f'attachment; filename="{name}"'
        return response
