"""A spreadsheet opening segments.csv shows what people typed, never runs it."""

import csv
import io

import pytest

from events.services import notes, segments
from tests.support.api import streamed

pytestmark = pytest.mark.django_db

FORMULAS = ['=HYPERLINK("http://x","y")', "+1+1", "-2+3", "@SUM(A1)", "\tx", "\rx"]


def test_formula_cells_are_written_as_text(api_client, leg, person):
    master = segments.report_mode(leg, "ito").master
    child = master.children.get()
    segments.annotate_segment(child, obstacle=FORMULAS[0], lighting=FORMULAS[1], slope=FORMULAS[2])
    notes.add_note(master, text=FORMULAS[3], author=person)
    response = api_client("viewer").get(
        f"/api/reports/exports/{leg.shift.test_event_id}/segments.csv"
    )
    assert response.status_code == 200
    rows = list(csv.DictReader(io.StringIO(streamed(response).decode())))
    reason = next(r for r in rows if r["row"] == "reason")
    assert (reason["obstacle"], reason["lighting"], reason["slope"]) == (
        "'" + FORMULAS[0],
        "'" + FORMULAS[1],
        "'" + FORMULAS[2],
    )
    cells = [cell for row in rows for cell in row.values()]
    assert not any(c.startswith(("=", "+", "@", "\t", "\r")) for c in cells if isinstance(c, str))
