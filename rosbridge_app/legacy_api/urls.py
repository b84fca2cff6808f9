from django.urls import path

from rosbridge_app.legacy_api import views

urlpatterns = [
    path("<str:token>/segment", views.SegmentView.as_view()),
    path("<str:token>/pose", views.PoseView.as_view()),
    path("<str:token>/local_pose", views.LocalPoseView.as_view()),
    path("<str:token>/map_image", views.MapImageView.as_view()),
    path("<str:token>/image", views.ImageView.as_view()),
    path("<str:token>/robot_state", views.RobotStateView.as_view()),
]
