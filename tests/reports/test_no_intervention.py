"""A run without a single intervention: the reader must see a lower bound, not a number.

With no intervention MDBI and MTBI are censored: the report prints "≥ exposure"
and an open upper bound ("∞"); a point estimate there would claim a precision
the data does not have.
"""

import pytest

from events.services import logs
from reports.documents.event_report import render_report
from reports.documents.options import ReportOptions
from telemetry.services import pose_writes
from tests.support.pdf import has_row, pdf_text
from tests.support.scenario import CHI2_95, STEP_M, T0, _at, _fixes, _switch


def m(steps: float) -> str:
    return f"{steps * STEP_M:.2f} m"


@pytest.fixture
def calm_event(vehicle, performer, media_root):
    """AUTO 0-100 s (3 steps), ITO at a goal (no intervention), AUTO 130-200 s (2 steps)."""
    event = logs.create_test_event(location="Ruhige Wiese", time_zone="UTC", at=T0)
    shift = logs.create_shift(test_event=event, vehicle=vehicle, performer=performer, at=T0)
    leg = logs.create_leg(shift=shift, at=T0)
    _switch(leg, "auto", T0, 0, 0.000)
    _switch(leg, "ito", T0, 100, 0.003, reason="goal")
    last = _switch(leg, "auto", T0, 130, 0.004)
    pose_writes.store_poses(last, _fixes(T0, [(150, 0.005), (190, 0.006)]))
    logs.close_test_event(event, at=_at(T0, 200))
    return event


def test_statistics_api_marks_the_estimates_as_censored(calm_event, api_client):
    data = api_client("viewer").get(f"/api/reports/statistics/{calm_event.pk}/").json()
    overall = data["overall"]
    assert overall["interventions"] == 0
    assert overall["mdbi"]["censored"] is True
    assert overall["mdbi"]["value"] is None and overall["mdbi"]["upper"] is None
    assert overall["mdbi"]["exposure"] == pytest.approx(5 * STEP_M)
    assert overall["mdbi"]["lower"] == pytest.approx(2 * 5 * STEP_M / CHI2_95[2], rel=1e-5)
    assert overall["mtbi"]["exposure"] == pytest.approx(170)


def test_pdf_shows_lower_bounds_and_an_open_upper_bound(calm_event, tmp_path):
    text = pdf_text(render_report(calm_event, ReportOptions(no_tiles=True)).pdf, tmp_path)
    assert has_row(text, "Interventions", "0")
    assert has_row(text, "MDBI", f"≥ {m(5)}")
    assert has_row(text, "MTBI", "≥ 0:02:50")
    assert has_row(text, "MDBI 90 % bounds", f"{m(2 * 5 / CHI2_95[2])} – ∞")
