"""Archive download for the GUI and archive import for administrators.

GET  /api/test-events/{id}/archive/   one test event as an FTT archive (viewers)
POST /api/archives/import/            multipart "archive" (+ "dry_run"), administrators:
                                      a dry run answers 200 with the plan; an import is
                                      checked the same way, then queued (202)
GET  /api/archives/imports/{id}/      a queued import and its outcome (administrators)
"""

import os
import tempfile
from pathlib import Path

from django.http import FileResponse
from django.shortcuts import get_object_or_404
from django.urls import path
from django.utils import timezone
from django.utils.translation import gettext
from drf_spectacular.types import OpenApiTypes
from drf_spectacular.utils import OpenApiResponse, extend_schema, inline_serializer
from rest_framework import serializers
from rest_framework.parsers import MultiPartParser
from rest_framework.response import Response
from rest_framework.views import APIView

from common import roles
from events.models import TestEvent
from exchange.archive import ArchiveError
from exchange.export import ExportError, export_events
from exchange.importer import ImportRefused, MalformedRecord
from exchange.models import ArchiveImport
from exchange.uploads import import_upload, queue_import


def _error(message: str, status: int) -> Response:
    return Response({"detail": message, "errors": {}}, status=status)


def temporary_download(write, filename: str) -> FileResponse:
    """Build a file with ``write(path)`` and stream it; the file is gone once sent."""
    with tempfile.TemporaryDirectory(prefix="ftt-download-") as scratch:
        target = Path(scratch) / filename
        write(target)
        handle = open(target, "rb")  # noqa: SIM115 - FileResponse closes it
        os.unlink(target)  # the open handle keeps the data until the response is sent
    return FileResponse(
        handle, as_attachment=True, filename=filename, content_type="application/zip"
    )


def stamped(prefix: str) -> str:
    return f"{prefix}-{timezone.now():%Y%m%d-%H%M%S}.zip"


ZIP_DOWNLOAD = {(200, "application/zip"): OpenApiTypes.BINARY}


class TestEventArchiveView(APIView):
    read_role = roles.VIEWER

    @extend_schema(responses=ZIP_DOWNLOAD, summary="Download a test event as an FTT archive")
    def get(self, request, pk: int):
        event = get_object_or_404(TestEvent, pk=pk)
        try:
            return temporary_download(
                lambda target: export_events(target, [event]),
                stamped(f"ftt-test-event-{event.pk}"),
            )
        except ExportError as exc:
            return _error(str(exc), 409)


class ArchiveImportView(APIView):
    write_role = roles.ADMINISTRATOR
    parser_classes = [MultiPartParser]

    @extend_schema(
        summary="Import an FTT archive (administrators)",
        request={
            "multipart/form-data": inline_serializer(
                "ArchiveUpload",
                {"archive": serializers.FileField(), "dry_run": serializers.BooleanField()},
            )
        },
        responses={
            202: OpenApiResponse(description="Checked and queued; 'job' tells where to follow it."),
            200: inline_serializer(
                "ImportPlan",
                {
                    "detail": serializers.CharField(),
                    "dry_run": serializers.BooleanField(),
                    "changes": serializers.IntegerField(),
                    "counts": serializers.DictField(),
                },
            ),
            400: OpenApiResponse(description="Not an FTT archive, damaged or malformed."),
            409: OpenApiResponse(description="Conflicts with data here; nothing changed."),
        },
    )
    def post(self, request):
        upload = request.FILES.get("archive")
        if upload is None:
            return _error("Send the archive file in the form field 'archive'.", 400)
        dry_run = str(request.data.get("dry_run", "")).lower() in ("1", "true", "yes", "on")
        try:
            if dry_run:
                plan, job = import_upload(upload, dry_run=True, by=request.user), None
            else:
                job, plan = queue_import(upload, user=request.user)
        except (ArchiveError, MalformedRecord) as exc:
            return _error(str(exc), 400)
        except ImportRefused as exc:
            return _error(str(exc), 409)
        body = {
            "detail": plan.verdict(),
            "dry_run": dry_run,
            "changes": plan.changes(),
            "counts": _counts(plan.counts),
        }
        if job is None:
            return Response(body)
        body["detail"] = gettext("Import queued as job %(job)s. %(verdict)s") % {
            "job": job.pk,
            "verdict": plan.verdict(),
        }
        return Response({**body, **_job(job, request)}, status=202)


def _counts(counts) -> dict:
    return {table: dict(c) for table, c in counts.items()}


def _job(job: ArchiveImport, request) -> dict:
    return {
        "job": {
            "id": job.pk,
            "status": job.status,
            "message": job.shown_message,
            "filename": job.filename,
            "detail": job.shown_verdict,
            "changes": job.changes,
            "counts": job.counts,
            "error": job.shown_error,
            "created": job.created,
            "finished": job.finished,
            "url": request.build_absolute_uri(f"/api/archives/imports/{job.pk}/"),
        }
    }


class ArchiveImportJobView(APIView):
    read_role = roles.ADMINISTRATOR

    @extend_schema(summary="A queued archive import and its outcome", responses={200: dict})
    def get(self, request, pk: int):
        return Response(_job(get_object_or_404(ArchiveImport, pk=pk), request)["job"])


urlpatterns = [
    path(
        "test-events/<int:pk>/archive/",
        TestEventArchiveView.as_view(),
        name="test-event-archive",
    ),
    path("archives/import/", ArchiveImportView.as_view(), name="archive-import"),
    path("archives/imports/<int:pk>/", ArchiveImportJobView.as_view(), name="archive-import-job"),
]
