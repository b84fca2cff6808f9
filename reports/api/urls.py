from django.urls import path, re_path

from reports.api import views

urlpatterns = [
    path("", views.ReportListView.as_view(), name="report-list"),
    path("compare/", views.ComparisonView.as_view(), name="report-compare"),
    path("routes/", views.RouteComparisonView.as_view(), name="report-routes"),
    path("choices/", views.ReportChoicesView.as_view(), name="report-choices"),
    path("<int:pk>/", views.ReportDetailView.as_view(), name="report-detail"),
    path("<int:pk>/pdf/", views.ReportPdfView.as_view(), name="report-pdf"),
    path("<int:pk>/verify/", views.ReportVerifyView.as_view(), name="report-verify"),
    path("verify/", views.VerifyUploadView.as_view(), name="report-verify-upload"),
    path(
        "amendments/<int:test_event_id>/",
        views.AmendmentsView.as_view(),
        name="report-amendments",
    ),
    path(
        "statistics/<int:test_event_id>/",
        views.StatisticsView.as_view(),
        name="report-statistics",
    ),
    path("test-plan/<int:test_event_id>/", views.TestPlanView.as_view(), name="report-test-plan"),
    path("judgements/", views.JudgementView.as_view(), name="report-judgements"),
    re_path(
        r"^exports/(?P<test_event_id>\d+)/(?P<filename>segments\.csv|disengagements\.csv"
        r"|autonomous-mileage\.csv"
        r"|tracks\.geojson|tracks\.gpx|test-plan\.csv|test-plan\.json)$",
        views.ExportView.as_view(),
        name="report-export",
    ),
]
