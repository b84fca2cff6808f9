from django.contrib import admin
from django.urls import include, path

from ftt_site import health, metrics

# Here rather than at start-up: see ftt_site.admin_site.FttAdminConfig.
admin.autodiscover()

urlpatterns = [
    path("healthz", health.healthz, name="healthz"),
    path("readyz", health.readyz, name="readyz"),
    path("metrics", metrics.metrics, name="metrics"),
    path("admin/", admin.site.urls),
    path("api/", include("ftt_site.api_urls")),
    path("tiles/", include("basemaps.urls")),
    path("legacy/", include("rosbridge_app.legacy_api.urls")),
    path("", include("gui.urls")),
]

# Under /api/ a wrong address or a crash outside DRF still answers JSON.
handler404 = "common.api.errors.not_found"
handler500 = "common.api.errors.server_error"
