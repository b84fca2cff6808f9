"""The PDF report of a test event."""

import tempfile
import time
from collections.abc import Callable
from contextlib import AbstractContextManager, nullcontext
from dataclasses import dataclass
from pathlib import Path

from events.models import TestEvent
from reports.documents.options import ReportError, ReportOptions
from reports.documents.sections import Sections
from reports.documents.typesetting import typeset
from reports.figures import style
from reports.formatting import written_in
from reports.selectors.content import has_segments

Progress = Callable[[float, str], None]
# Wraps each stage of making a report (statistics, maps, charts, timelines, image
# encoding, typst), by its name; benchmarks/report_benchmark.py times them.
StageHook = Callable[[str], AbstractContextManager]


@dataclass
class ReportResult:
    pdf: bytes
    pages_hint: int
    provisional: bool
    tiles_used: bool
    seconds: float
    warnings: list[str]


def _silent(_fraction: float, _message: str) -> None:
    pass


def _untimed(_stage: str) -> AbstractContextManager:
    return nullcontext()


def check_reportable(event: TestEvent) -> None:
    if not has_segments(event):
        raise ReportError(
            f"Test event {event.pk} ('{event}') has no segments yet: nothing to report."
        )


def render_report(
    event: TestEvent,
    options: ReportOptions,
    progress: Progress = _silent,
    *,
    time_stage: StageHook = _untimed,
) -> ReportResult:
    """The finished PDF as bytes; raises ReportError for a test event without data."""
    started = time.perf_counter()
    check_reportable(event)
    style.apply()
    with (
        tempfile.TemporaryDirectory(prefix="ftt-report-") as tmp,
        written_in(options.language or event.language),
    ):
        sections = Sections(event, options, Path(tmp), progress, time_stage)
        data = sections.document()
        progress(0.95, "typesetting")
        with time_stage("typst"):
            pdf = typeset("report.typ", data, Path(tmp))
    progress(1.0, "done")
    return ReportResult(
        pdf=pdf,
        pages_hint=len(data["shifts"]),
        provisional=data["provisional"],
        tiles_used=sections.tiles_used,
        seconds=time.perf_counter() - started,
        warnings=sections.warnings,
    )
