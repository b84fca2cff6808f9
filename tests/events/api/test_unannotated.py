"""Whether a take-over reason has no annotation yet is the server's word
(``Segment.unannotated``): the rows say it and the cockpit draws from them."""

from datetime import UTC, datetime, timedelta
from pathlib import Path

from common import roles
from events.models import ItoReason, SegmentType
from events.services import segments
from reports.selectors.statistics import counted_reason

ROOT = Path(__file__).resolve().parents[3]


def test_a_take_over_reason_is_unannotated_until_it_is_given_one(api_client, leg):
    at = datetime.now(UTC) + timedelta(minutes=5)
    segments.report_mode(leg, SegmentType.AUTO, at=at)
    master = segments.report_mode(leg, SegmentType.ITO, at=at + timedelta(seconds=5)).master
    child = master.children.get()
    client = api_client(roles.VIEWER)

    def rows():
        answer = client.get("/api/segments/", {"leg": leg.pk, "page_size": 50})
        assert answer.status_code == 200, answer.content
        return {r["id"]: r for r in answer.json()["results"]}

    shown = rows()
    assert shown[child.pk]["ito_reason"] == ItoReason.UNASSIGNED
    assert shown[child.pk]["unannotated"] is True
    assert shown[master.pk]["unannotated"] is False  # a master carries no annotation
    assert counted_reason(child) == ItoReason.UNASSIGNED

    segments.annotate_segment(child, ito_reason="safety")
    assert rows()[child.pk]["unannotated"] is False
    child.refresh_from_db()
    assert counted_reason(child) == "safety"


def test_the_cockpit_scripts_never_decide_it_themselves():
    """A copy of the rule in the browser would name the Unassigned reason's key."""
    copies = [
        path.name
        for path in sorted((ROOT / "static" / "gui").glob("*.js"))
        if f'"{ItoReason.UNASSIGNED}"' in path.read_text(encoding="utf-8")
    ]
    assert copies == []
