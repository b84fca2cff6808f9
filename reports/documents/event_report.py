"""The PDF report of a test event."""

import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from django.utils.translation import gettext_noop

from common import cyclic_gc
from common.deferred_text import DeferredText, deferred
from events.models import TestEvent
from reports.charts import style
from reports.documents.options import ReportError, ReportOptions
from reports.documents.sections import Sections
from reports.documents.stage_times import StageTimes
from reports.documents.typesetting import typeset
from reports.formatting import written_in
from reports.selectors.content import has_segments, report_scope, scope_text
from reports.selectors.provenance import seal_pdf

Progress = Callable[[float, DeferredText], None]


@dataclass
class ReportResult:
    pdf: bytes
    pages_hint: int
    provisional: bool
    tiles_used: bool
    seconds: float
    warnings: list[str]
    stages: StageTimes


def _silent(_fraction: float, _step: DeferredText) -> None:
    pass


def check_reportable(event: TestEvent, options: ReportOptions | None = None) -> None:
    """Raises ReportError when the test event, or the shift or leg asked for, is not
    part of it or has no segments; sets the shift of a leg asked for alone."""
    scope = options.scope if options is not None else {}
    try:
        found = report_scope(event, **scope)
    except ValueError as exc:
        raise ReportError(" ".join(m for ms in exc.args[0].values() for m in ms)) from None
    if options is not None:
        options.shift, options.leg = found
        scope = options.scope
    if not has_segments(event, **scope):
        if options is not None and (options.shift or options.leg):
            raise ReportError(
                gettext_noop(
                    "%(scope)s of test event %(event)s has no segments yet: nothing to report."
                ),
                scope=scope_text(**scope),
                event=event.pk,
            )
        raise ReportError(
            gettext_noop("Test event %(id)s ('%(event)s') has no segments yet: nothing to report."),
            id=event.pk,
            event=str(event),
        )


@cyclic_gc.paused()
def render_report(
    event: TestEvent,
    options: ReportOptions,
    progress: Progress = _silent,
) -> ReportResult:
    """The finished PDF as bytes; raises ReportError for a test event without data."""
    started = time.perf_counter()
    stages = StageTimes()
    check_reportable(event, options)
    style.apply()
    with (
        tempfile.TemporaryDirectory(prefix="ftt-report-") as tmp,
        written_in(options.language or event.language),
    ):
        sections = Sections(event, options, Path(tmp), progress, stages.timed)
        data = sections.document()
        progress(0.95, deferred(gettext_noop("typesetting")))
        with stages.timed(gettext_noop("typesetting")):
            pdf = seal_pdf(typeset("report.typ", data, Path(tmp)))
    progress(1.0, deferred(gettext_noop("done")))
    return ReportResult(
        pdf=pdf,
        pages_hint=len(data["shifts"]),
        provisional=data["provisional"],
        tiles_used=sections.tiles_used,
        seconds=time.perf_counter() - started,
        warnings=sections.warnings,
        stages=stages,
    )
