"""Operator GUI pages and the few JSON reads only the GUI needs."""

from django.contrib.auth import views as auth_views
from django.urls import path, re_path

from gui.views import archive_import, gui_api, media, pages

urlpatterns = [
    path("", pages.index, name="gui-index"),
    path("favicon.ico", pages.favicon, name="favicon"),
    path("sw.js", pages.service_worker, name="gui-service-worker"),
    path("compare/", pages.compare, name="gui-compare"),
    path(
        "login/",
        auth_views.LoginView.as_view(redirect_authenticated_user=True),
        name="login",
    ),
    path("logout/", auth_views.LogoutView.as_view(), name="logout"),
    path("import/", archive_import.archive_import, name="gui-archive-import"),
    path("gui/api/legs/<int:pk>/tracks/", gui_api.LegTracks.as_view(), name="gui-leg-tracks"),
    path(
        "gui/api/legs/<int:pk>/distances/",
        gui_api.LegDistances.as_view(),
        name="gui-leg-distances",
    ),
    path("gui/api/legs/<int:pk>/segments/", gui_api.LegSegments.as_view(), name="gui-segments"),
    path(
        "gui/api/legs/<int:pk>/manual-segment/",
        gui_api.ManualSegment.as_view(),
        name="gui-manual-segment",
    ),
    path(
        "gui/api/segments/<int:pk>/close/",
        gui_api.SegmentClose.as_view(),
        name="gui-segment-close",
    ),
    path(
        "gui/api/legs/<int:pk>/quick-reason/",
        gui_api.QuickReason.as_view(),
        name="gui-quick-reason",
    ),
    path(
        "gui/api/segments/<int:pk>/attachments/",
        gui_api.SegmentAttachments.as_view(),
        name="gui-segment-attachments",
    ),
    path("gui/api/shifts/<int:pk>/local-map/", gui_api.ShiftLocalMap.as_view(), name="gui-map"),
    path("gui/api/basemaps/", gui_api.Basemaps.as_view(), name="gui-basemaps"),
    path("gui/api/collectors/", gui_api.CollectorStatus.as_view(), name="gui-collectors"),
    path("gui/api/fleet/", gui_api.Fleet.as_view(), name="gui-fleet"),
    path("gui/api/ending/", gui_api.Ending.as_view(), name="gui-ending"),
    path("gui/api/forms/", gui_api.Forms.as_view(), name="gui-forms"),
    path("gui/api/test-case-areas/", gui_api.TestCaseAreas.as_view(), name="gui-test-case-areas"),
    path(
        "gui/api/test-case-routes/", gui_api.TestCaseRoutes.as_view(), name="gui-test-case-routes"
    ),
    path(
        "gui/api/collectors/<int:pk>/commands/",
        gui_api.CollectorCommands.as_view(),
        name="gui-collector-commands",
    ),
    # Photos and maps are field data: only logged-in users with a role see them.
    re_path(r"^media/(?P<path>.+)$", media.protected_media, name="gui-media"),
]
