"""Map tiles of FTT's own layers, for signed-in users with a role."""

from django.http import Http404, HttpResponse
from django.shortcuts import get_object_or_404
from django.utils.cache import patch_cache_control, patch_vary_headers
from django.utils.translation import gettext

from basemaps.mbtiles import TooCostly
from basemaps.models import BasemapLayer
from basemaps.selectors.tiles import render_tile
from common import roles
from common.api.errors import RETRY_AFTER_SECONDS

CONTENT_TYPES = {"png": "image/png", "webp": "image/webp"}
# A layer's file does not change under its key without ``modified`` changing,
# which is part of the ETag; a day keeps panning smooth without going stale long.
MAX_AGE = 24 * 3600


def tile(request, key, z, x, y, fmt):
    user = request.user
    if not user.is_authenticated:
        return HttpResponse(
            gettext("Sign in to see map tiles."), status=401, content_type="text/plain"
        )
    if not roles.has_role(user, roles.VIEWER):
        return HttpResponse(
            gettext("Your account has no role."), status=403, content_type="text/plain"
        )
    layer = get_object_or_404(BasemapLayer, key=key)
    try:
        data = render_tile(layer, z, x, y, fmt)
    except TooCostly:
        response = HttpResponse(
            gettext("This map file did not give the tile in time; try again later."),
            status=503,
            content_type="text/plain",
        )
        response["Retry-After"] = str(RETRY_AFTER_SECONDS)
        return response
    if data is None:
        raise Http404("No tile here.")
    response = HttpResponse(data, content_type=CONTENT_TYPES[fmt])
    response["ETag"] = f'"{layer.pk}-{layer.modified.timestamp():.0f}-{z}-{x}-{y}.{fmt}"'
    # private: the tiles are field data behind a login, not for shared caches.
    patch_cache_control(response, private=True, max_age=MAX_AGE)
    patch_vary_headers(response, ["Cookie"])
    return response
