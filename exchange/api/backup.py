"""GET /api/backup/: the whole database and media files, for administrators."""

from django.urls import path
from drf_spectacular.utils import extend_schema
from rest_framework.response import Response
from rest_framework.views import APIView

from common import roles
from exchange.api.archives import ZIP_DOWNLOAD, stamped, temporary_download
from exchange.backup import BackupError, make_backup


class BackupView(APIView):
    read_role = roles.ADMINISTRATOR

    @extend_schema(responses=ZIP_DOWNLOAD, summary="Download a whole-database backup")
    def get(self, request):
        try:
            return temporary_download(make_backup, stamped("ftt-backup"))
        except BackupError as exc:
            return Response({"detail": str(exc), "errors": {}}, status=500)


urlpatterns = [path("backup/", BackupView.as_view(), name="backup")]
