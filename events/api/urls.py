from django.urls import path
from rest_framework.routers import SimpleRouter

from common.api.tokens import obtain_token
from events.api import views

router = SimpleRouter()
router.register("test-events", views.TestEventViewSet, basename="test-event")
router.register("shifts", views.ShiftViewSet, basename="shift")
router.register("legs", views.LegViewSet, basename="leg")
router.register("segments", views.SegmentViewSet, basename="segment")
router.register("notes", views.NoteViewSet, basename="note")
router.register("personnel", views.PersonnelViewSet, basename="personnel")
router.register("performers", views.PerformerViewSet, basename="performer")
router.register("vehicles", views.VehicleViewSet, basename="vehicle")
router.register("pose-sources", views.PoseSourceViewSet, basename="pose-source")
router.register("weather", views.WeatherViewSet, basename="weather")
router.register("ito-reasons", views.ItoReasonViewSet, basename="ito-reason")
router.register("segment-types", views.SegmentTypeViewSet, basename="segment-type")

urlpatterns = [
    # POST username + password, get {"token": ...}; send it as "Authorization: Token <key>".
    path("token/", obtain_token, name="api-token"),
    *router.urls,
]
