from rest_framework.routers import SimpleRouter

from telemetry.api import views

router = SimpleRouter()
router.register("poses", views.PoseViewSet, basename="pose")
router.register("local-poses", views.LocalPoseViewSet, basename="local-pose")
router.register("maps", views.MapImageViewSet, basename="map")
router.register("images", views.ImageViewSet, basename="image")
router.register("recordings", views.RecordingFileViewSet, basename="recording")
router.register("tracks", views.TrackViewSet, basename="track")
router.register("local-tracks", views.LocalTrackViewSet, basename="local-track")

urlpatterns = router.urls
