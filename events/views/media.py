from django.conf import settings
from django.core.exceptions import PermissionDenied
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
    return serve(request, path, document_root=settings.MEDIA_ROOT)
