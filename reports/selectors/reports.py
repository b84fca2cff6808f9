from reports.models import Report


def reports_of(test_event_id: int | None = None):
    """Kept reports, newest first; of one test event when an id is given."""
    rows = Report.objects.all()
    if test_event_id is not None:
        rows = rows.filter(test_event_id=test_event_id)
    return rows.order_by("-created", "-id")
