import mimetypes
import posixpath
from pathlib import Path
from urllib.parse import quote

from django.conf import settings
from django.core.exceptions import PermissionDenied
from django.http import Http404, HttpResponse
from django.views.static import serve
from rest_framework.authentication import TokenAuthentication
from rest_framework.exceptions import AuthenticationFailed

from events import roles


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
        return _handed_to_the_proxy(prefix, path)
    return serve(request, path, document_root=settings.MEDIA_ROOT)


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
    content_type, _ = mimetypes.guess_type(clean)
    response = HttpResponse(content_type=content_type or "application/octet-stream")
    response["X-Accel-Redirect"] = prefix.rstrip("/") + "/" + quote(clean)
    return response
