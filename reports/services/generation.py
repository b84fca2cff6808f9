"""Reports requested from the GUI or the API: queued, made in the background, kept.

:func:`request_report` stores a ``Report`` row and, in the same transaction,
enqueues the job that makes it (common/jobs.py: django-tasks in FTT's own
database), so it returns at once and survives restarts. ``manage.py
ftt_worker`` makes the PDF and records its progress on the row, so the GUI can
poll it; a worker that dies mid-report has the report retried once, then
failed with the reason. Every report is kept with its test event for download.
One report is made at a time per worker: the machine is small and the figures
are CPU-bound; the others wait as "queued".
"""

import logging
import math
import threading
import time

from django.conf import settings
from django.contrib.auth import get_user_model
from django.core.exceptions import ValidationError
from django.core.files.base import ContentFile
from django.db import transaction
from django.utils import timezone
from django.utils.translation import gettext as _
from django.utils.translation import gettext_noop
from django_tasks import task

from common import jobs
from common.deferred_text import DeferredText, deferred, deferred_fields
from common.errors import RuleViolation, TooManyWaiting
from events.models import TestEvent
from reports.documents.comparison import render_comparison
from reports.documents.event_report import ReportResult, check_reportable, render_report
from reports.documents.options import ReportError, ReportOptions, language_problem
from reports.documents.stage_times import StageTimes
from reports.models import Report
from reports.selectors.content import report_scope
from reports.selectors.routes import (
    DEFAULT_THRESHOLD,
    RouteChoiceError,
    check_route_choice,
    check_threshold,
)

log = logging.getLogger(__name__)

_ONE_AT_A_TIME = threading.Semaphore(1)
PROGRESS_INTERVAL_S = 0.5


def request_report(
    test_event: TestEvent,
    options: dict | ReportOptions | None = None,
    *,
    user=None,
    shift: int | None = None,
    leg: int | None = None,
) -> Report:
    """Queue a report of the test event, or of one ``shift`` or ``leg`` of it
    (ids); returns the new row."""
    opts = options if isinstance(options, ReportOptions) else _checked_options(options or {})
    try:
        opts.shift, opts.leg = report_scope(test_event, shift=shift, leg=leg)
    except ValueError as exc:
        raise ValidationError(exc.args[0]) from None
    try:
        check_reportable(test_event, opts)
    except ReportError as exc:
        raise RuleViolation(str(exc), code="empty") from None
    with transaction.atomic():
        check_waiting(user)
        report = Report.objects.create(
            test_event=test_event,
            options=opts.as_dict(),
            requested_by=user if user is not None and user.is_authenticated else None,
            **deferred_fields("message", jobs.waiting()),
        )
        make_report.enqueue(report.pk)
    return report


COMPARE = "compare"  # the options key that makes a row a comparison of these test events
# A comparison's routes to overlay: {"leg": [ids], "case": [ids], "threshold": metres}.
ROUTES = "routes"


def request_comparison(
    test_events: list[TestEvent], options: dict | None = None, *, user=None
) -> Report:
    """Queue a comparison of several test events (a PDF like the others); the row
    is kept with the first of them and lists all under ``options["compare"]``."""
    options = options or {}
    if not isinstance(options, dict):
        raise ValidationError({"options": [_("Options must be an object.")]})
    unknown = sorted(set(options) - {"local", "language", ROUTES})
    errors = [
        _("Unknown or not requestable option '%(key)s' for a comparison.") % {"key": key}
        for key in unknown
    ]
    if "local" in options and not isinstance(options["local"], bool):
        errors.append(_("Option 'local' must be true or false."))
    language = options.get("language") or ""
    if problem := language_problem(str(language)):
        errors.append(problem)
    routes = route_option(options.get(ROUTES), errors)
    if errors:
        raise ValidationError({"options": errors})
    if len({e.pk for e in test_events}) < 2:
        raise ValidationError({"compare": [_("Give at least two different test events.")]})
    events = sorted(test_events, key=lambda e: (e.start, e.pk))
    with transaction.atomic():
        check_waiting(user)
        report = Report.objects.create(
            test_event=events[0],
            options={
                COMPARE: [e.pk for e in events],
                "local": bool(options.get("local", False)),
                "language": language,
                **({ROUTES: routes} if routes else {}),
            },
            requested_by=user if user is not None and user.is_authenticated else None,
            **deferred_fields("message", jobs.waiting()),
        )
        make_report.enqueue(report.pk)
    return report


def route_option(value, errors: list) -> dict | None:
    """The comparison's routes option ({"leg": [ids], "case": [ids], "threshold":
    metres}), checked as the route API checks its query: the checked option, or
    None with the problems appended to ``errors`` (None without errors: no routes).
    ``manage.py ftt_report --compare --route-leg …`` goes through it too."""
    if value is None:
        return None
    if not isinstance(value, dict) or set(value) - {"leg", "case", "threshold"}:
        errors.append(_("Option 'routes' is an object with 'leg', 'case' and 'threshold'."))
        return None
    legs, cases = value.get("leg", []), value.get("case", [])
    threshold = value.get("threshold", DEFAULT_THRESHOLD)
    ids = [*legs, *cases] if isinstance(legs, list) and isinstance(cases, list) else None
    if ids is None or not all(isinstance(i, int) and not isinstance(i, bool) for i in ids):
        errors.append(_("Option 'routes' names legs and test cases by their ids (numbers)."))
        return None
    if isinstance(threshold, bool) or not isinstance(threshold, int | float):
        threshold = -1.0
    try:
        threshold = check_threshold(threshold)
        check_route_choice(legs, cases)
    except RouteChoiceError as error:
        errors.append(str(error))
        return None
    return {"leg": legs, "case": cases, "threshold": threshold}


def check_waiting(user) -> None:
    """Refuse a report when ``user`` already has FTT_MAX_WAITING_REPORTS queued or
    running; call inside the transaction that queues it."""
    if user is None or not user.is_authenticated:
        return
    # One request of this account at a time past this point: the count holds.
    list(get_user_model().objects.select_for_update().filter(pk=user.pk).values_list("pk"))
    waiting = Report.objects.filter(
        requested_by=user, status__in=[Report.Status.QUEUED, Report.Status.RUNNING]
    ).count()
    limit = settings.FTT_MAX_WAITING_REPORTS
    if waiting >= limit:
        raise TooManyWaiting(
            (
                _(
                    "You have %(waiting)s reports waiting or being made, the most one "
                    "account may have (FTT_MAX_WAITING_REPORTS=%(limit)s); request more "
                    "when they are done."
                )
                % {"waiting": waiting, "limit": limit}
            ),
            code="too_many_waiting",
        )


@task()
def make_report(report_id: int) -> str:
    """The queued job: make the PDF of a report row."""
    return run_job(report_id).status


@jobs.when_interrupted(make_report)
def _worker_stopped(report_id: int, *, retried: bool, reason: DeferredText) -> None:
    if retried:
        Report.objects.filter(pk=report_id).update(
            status=Report.Status.QUEUED,
            progress=0.0,
            **deferred_fields(
                "message", deferred(gettext_noop("queued again: %(reason)s"), reason=reason), 200
            ),
            updated=timezone.now(),
        )
    else:
        _fail(
            report_id, deferred(gettext_noop("%(reason)s Request the report again."), reason=reason)
        )


# A requested report reads no file and fetches no URL chosen by the requester:
# the logo and tile server are the site's (FTT_TILE_URL), settable on the CLI only.
REQUESTABLE = {
    "name": str,
    "version": str,
    "recipient": str,
    "recipient_address": list,
    "creator": str,
    "creator_address": list,
    "local": bool,
    "no_tiles": bool,
    "min_timeline_hours": float,
    "max_zoom": int,
    "level": str,
    "image_appendix": bool,
    "language": str,
}


def _checked_options(options: dict) -> ReportOptions:
    if not isinstance(options, dict):
        raise ValidationError({"options": [_("Options must be an object.")]})
    errors = []
    for key, value in options.items():
        kind = REQUESTABLE.get(key)
        if kind is None:
            errors.append(_("Unknown or not requestable option '%(key)s'.") % {"key": key})
        elif not _is_a(value, kind):
            expected = {
                str: _("Option '%(key)s' must be text."),
                list: _("Option '%(key)s' must be a list of text lines."),
                bool: _("Option '%(key)s' must be true or false."),
                float: _("Option '%(key)s' must be a number."),
                int: _("Option '%(key)s' must be a whole number."),
            }[kind]
            errors.append(expected % {"key": key})
    if errors:
        raise ValidationError({"options": errors})
    checked = ReportOptions.from_dict(options)
    if problems := checked.problems():
        raise ValidationError({"options": problems})
    return checked


def _is_a(value, kind) -> bool:
    if isinstance(value, bool):  # JSON true is no number
        return kind is bool
    if kind is float:
        return isinstance(value, int | float) and math.isfinite(value)
    if kind is list:
        return isinstance(value, list) and all(isinstance(line, str) for line in value)
    return isinstance(value, kind)


def run_job(report_id: int) -> Report:
    """Make the PDF of a queued report row (worker side); never raises for bad data."""
    with _ONE_AT_A_TIME:
        report = Report.objects.select_related("test_event").get(pk=report_id)
        if report.is_finished:
            return report
        Report.objects.filter(pk=report_id).update(
            status=Report.Status.RUNNING,
            **deferred_fields("message", deferred(gettext_noop("starting"))),
            updated=timezone.now(),
        )
        last = [0.0]

        def progress(fraction: float, step: DeferredText) -> None:
            now = time.monotonic()
            if now - last[0] < PROGRESS_INTERVAL_S and fraction < 1.0:
                return
            last[0] = now
            Report.objects.filter(pk=report_id).update(
                progress=round(fraction, 3),
                **deferred_fields("message", step, 200),
                updated=timezone.now(),
            )

        try:
            result = _render(report, progress)
        except ReportError as exc:
            return _fail(report_id, exc.deferred)
        except Exception as exc:  # a worker must record every failure on its row
            log.exception("report %s failed", report_id)
            unexpected = gettext_noop("Unexpected error: %(kind)s: %(error)s")
            return _fail(
                report_id, deferred(unexpected, kind=exc.__class__.__name__, error=str(exc))
            )
        except BaseException:  # the worker was told twice to stop: it drops the report
            stopped = gettext_noop("The job worker was stopped while it made the report.")
            _fail(report_id, deferred(stopped))
            raise
        report.refresh_from_db()
        report.pdf.save(f"report-{report.pk}.pdf", ContentFile(result.pdf), save=False)
        report.status = Report.Status.DONE
        report.progress = 1.0
        report.message, report.message_said = "done", deferred(gettext_noop("done")).as_json()
        report.provisional = result.provisional
        report.finished = timezone.now()
        report.error, report.error_said = "\n".join(result.warnings), {}
        report.save()
        return report


def _render(report: Report, progress) -> ReportResult:
    ids = report.options.get(COMPARE)
    if not ids:
        return render_report(report.test_event, ReportOptions.from_dict(report.options), progress)
    events = list(TestEvent.objects.filter(pk__in=ids))
    if len(events) < 2:
        raise ReportError(
            gettext_noop("A test event of this comparison was deleted; request it again.")
        )
    progress(0.1, deferred(gettext_noop("comparing test events")))
    started = time.perf_counter()
    stages = StageTimes()
    mode = "local" if report.options.get("local") else "gps"
    with stages.timed(gettext_noop("comparing test events")):
        pdf = render_comparison(
            events, mode, report.options.get("language") or "", routes=report.options.get(ROUTES)
        )
    return ReportResult(
        pdf=pdf,
        pages_hint=0,
        provisional=False,
        tiles_used=False,
        seconds=time.perf_counter() - started,
        warnings=[],
        stages=stages,
    )


def _fail(report_id: int, why: DeferredText) -> Report:
    Report.objects.filter(pk=report_id).update(
        status=Report.Status.FAILED,
        **deferred_fields("error", why),
        **deferred_fields("message", deferred(gettext_noop("failed"))),
        finished=timezone.now(),
    )
    return Report.objects.get(pk=report_id)
