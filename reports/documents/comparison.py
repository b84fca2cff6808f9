"""The comparison report: several test events side by side, as a PDF.

The figures are the comparison selector's; this only formats them and lets
typst set them, with user text passed as JSON data, never as markup.
"""

import tempfile
from pathlib import Path

from events.models import ItoReason, TestEvent
from reports import formatting as fmt
from reports.documents.options import ReportError
from reports.documents.routes import routes_section
from reports.documents.typesetting import typeset
from reports.figures import style
from reports.figures.growth import growth_chart, hotspot_chart
from reports.selectors.comparison import compare
from telemetry.selectors.tracks import GPS


def _row(name: str, group: dict) -> list[str]:
    shown = group["shown"]
    return [name] + [
        shown[key]
        for key in (
            "interventions",
            "auto_distance",
            "mdbi",
            "mdbi_bounds",
            "mtbi",
            "mtbi_bounds",
            "per_km",
            "per_hour",
        )
    ]


def _hotspot_row(spot: dict, reasons: dict, names: dict) -> list[str]:
    """Number, take-overs, reasons with counts, and each take-over's segment."""
    reason_text = ", ".join(
        f"{reasons[key].short_description if key in reasons else key} ({count})"
        for key, count in spot["reasons"].items()
    )
    segments = "; ".join(
        f"{names.get(m['test_event'], m['test_event'])}: {m['label']}" for m in spot["members"]
    )
    return [str(spot["number"]), str(spot["count"]), reason_text or fmt.DASH, segments]


def render_comparison(
    events: list[TestEvent], mode: str = GPS, routes: dict | None = None
) -> bytes:
    """The PDF; ``routes`` ({"leg": [ids], "case": [ids], "threshold": metres}) adds
    the routes section."""
    if len(events) < 2:
        raise ReportError("A comparison needs at least two test events.")
    data = compare(events, mode)
    style.apply()
    reasons = {r.key: r for r in ItoReason.objects.all()}
    with tempfile.TemporaryDirectory(prefix="ftt-compare-") as tmp:
        root = Path(tmp)
        growth = data["growth"]
        growth_chart(growth["points"], growth["total_distance"], growth["fit"], root / "growth.svg")
        hotspots = hotspot_chart(data["hotspots"], reasons, root / "hotspots.svg")
        names = {e["id"]: e["name"] for e in data["test_events"]}
        document = {
            "events": [_row(f"{e['id']}: {e['name']}", e) for e in data["test_events"]],
            "versions": [_row(v["version"], v) for v in data["versions"]],
            "vehicles": [_row(v["name"], v) for v in data["vehicles"]],
            "growth": "growth.svg",
            "fit": growth["fit_rows"] or None,
            "hotspots": "hotspots.svg" if hotspots else None,
            "hotspot_note": f"Take-overs at most {data['hotspot_radius']:g} m apart form "
            "one hotspot (single linkage); numbers as on the map.",
            "hotspot_rows": [_hotspot_row(spot, reasons, names) for spot in data["hotspots"]],
            "formulas": [[k, v] for k, v in data["formulas"].items()],
            "routes": routes_section(routes, root) if routes else None,
        }
        return typeset("compare.typ", document, root)
