from django.contrib import admin
from django.urls import include, path

urlpatterns = [
    path("admin/", admin.site.urls),
    path("api/", include("ftt_site.api_urls")),
    path("", include("events.urls")),
]

# Under /api/ a wrong address or a crash outside DRF still answers JSON.
handler404 = "events.api.errors.not_found"
handler500 = "events.api.errors.server_error"
