from statistics import median

from reports.models import Report

# How many finished reports of a kind the expected time is read from.
RECENT = 20


def reports_of(test_event_id: int | None = None):
    """Kept reports, newest first; of one test event when an id is given."""
    rows = Report.objects.all()
    if test_event_id is not None:
        rows = rows.filter(test_event_id=test_event_id)
    return rows.order_by("-created", "-id")


def _kind(options: dict) -> tuple:
    """What makes reports take alike long: a comparison or not, the detail, the scope."""
    scope = "leg" if options.get("leg") else "shift" if options.get("shift") else "event"
    return (bool(options.get("compare")), options.get("level"), scope)


def expected_seconds(report: Report, memo: dict | None = None) -> float | None:
    """How long a report like ``report`` took, created to finished: the median of
    the last RECENT finished ones of its kind (None before the first); ``memo``
    keeps the answer per kind for a list of reports."""
    kind = _kind(report.options or {})
    memo = {} if memo is None else memo
    if kind not in memo:
        done = Report.objects.filter(status=Report.Status.DONE, finished__isnull=False)
        durations = [
            (r.finished - r.created).total_seconds()
            for r in done.order_by("-finished")[: RECENT * 10].only(
                "created", "finished", "options"
            )
            if _kind(r.options or {}) == kind
        ][:RECENT]
        memo[kind] = round(median(durations), 1) if durations else None
    return memo[kind]
