from django.contrib import admin
from django.urls import include, path
from django.views.i18n import JavaScriptCatalog

from ftt_site.inbound import language
from ftt_site.monitoring import health, metrics

# Here rather than at start-up: see ftt_site.admin_site.FttAdminConfig.
admin.autodiscover()

urlpatterns = [
    path("healthz", health.healthz, name="healthz"),
    path("readyz", health.readyz, name="readyz"),
    path("metrics", metrics.metrics, name="metrics"),
    path("admin/", admin.site.urls),
    # The GUI's strings in the page's language (static/gui/i18n.js), from locale/.
    path("jsi18n/", JavaScriptCatalog.as_view(), name="javascript-catalog"),
    path("language/", language.choose_language, name="choose-language"),
    path("api/", include("ftt_site.api_urls")),
    path("tiles/", include("basemaps.urls")),
    path("legacy/", include("rosbridge_app.legacy_api.urls")),
    path("", include("gui.urls")),
]

# Under /api/ a wrong address or a crash outside DRF still answers JSON.
handler404 = "common.api.errors.not_found"
handler500 = "common.api.errors.server_error"
