import posixpath
from pathlib import Path
from urllib.parse import quote

from django.conf import settings
from django.core.exceptions import PermissionDenied
from django.http import Http404, HttpResponse
from django.views.static import serve
from rest_framework.exceptions import AuthenticationFailed

from common import roles
from common.api.authentication import TokenAuthentication

# What /media/ shows in the browser: photos, maps and reports.  Anything else
# (recordings, or a file that got in some other way) is only downloaded, so a
# stored page or script never runs under FTT's origin.
INLINE_TYPES = {
    ".jpg": "image/jpeg",
    ".jpeg": "image/jpeg",
    ".png": "image/png",
    ".webp": "image/webp",
    ".pdf": "application/pdf",
}


def _typed(response: HttpResponse, path: str) -> HttpResponse:
    content_type = INLINE_TYPES.get(posixpath.splitext(path)[1].lower())
    if content_type is None:
        response["Content-Type"] = "application/octet-stream"
        response["Content-Disposition"] = "attachment"
    else:
        response["Content-Type"] = content_type
    return response


def _user(request):
    # Image and map URLs in API answers must open for token clients (robots,
    # scripts) as well as for the browser session.
    if request.user.is_authenticated:
        return request.user
    try:
        found = TokenAuthentication().authenticate(request)
    except AuthenticationFailed:
        return None
    return found[0] if found else None


def protected_media(request, path):
    if not roles.has_role(_user(request), roles.VIEWER):
        raise PermissionDenied
    prefix = settings.FTT_MEDIA_ACCEL_PREFIX
    if prefix:
        return _typed(_handed_to_the_proxy(prefix, path), path)
    return _typed(serve(request, path, document_root=settings.MEDIA_ROOT), path)


def _handed_to_the_proxy(prefix: str, path: str) -> HttpResponse:
    # The proxy trusts this header blindly, so only a plain path to an existing
    # file under MEDIA_ROOT may be named in it.
    clean = posixpath.normpath(path).lstrip("/")
    if clean.startswith("..") or "\\" in clean or "\0" in clean:
        raise Http404("No such file.")
    root = Path(settings.MEDIA_ROOT).resolve()
    target = (root / clean).resolve()
    if not target.is_relative_to(root) or not target.is_file():
        raise Http404("No such file.")
    response = HttpResponse()
    response["X-Accel-Redirect"] = prefix.rstrip("/") + "/" + quote(clean)
    return response
