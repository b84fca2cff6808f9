"""The comparison report: several test events side by side, as a PDF.

The figures are the comparison selector's; this only formats them and lets
typst set them, with user text passed as JSON data, never as markup.
"""

import tempfile
from pathlib import Path

from django.conf import settings
from django.utils import timezone
from django.utils.translation import gettext as _
from django.utils.translation import gettext_noop

from events.models import ItoReason, TestEvent
from reports import formatting as fmt
from reports.charts import style
from reports.charts.growth import growth_chart, hotspot_chart
from reports.documents.options import ReportError
from reports.documents.routes import routes_section
from reports.documents.typesetting import typeset
from reports.documents.wording import comparison_text
from reports.selectors.comparison import compare
from telemetry.storage.keys import GPS_TRACK


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
        f"{reasons[key].shown_short if key in reasons else key} ({count})"
        for key, count in spot["reasons"].items()
    )
    segments = "; ".join(
        f"{names.get(m['test_event'], m['test_event'])}: {m['label']}" for m in spot["members"]
    )
    return [str(spot["number"]), str(spot["count"]), reason_text or fmt.DASH, segments]


def comparison_language(events: list[TestEvent]) -> str:
    """The language the compared test events share, else the site's."""
    languages = {e.language for e in events}
    return languages.pop() if len(languages) == 1 else settings.LANGUAGE_CODE


def _event_name(event: TestEvent) -> str:
    """Place, first day (in the reader's date format), version and number."""
    name = event.location or _("Test event")
    if event.start:
        name += " " + fmt.day(event.start.astimezone(event.tzinfo).date())
    if event.version:
        name += f" · {event.version}"
    return f"{name} (#{event.pk})"


def render_comparison(
    events: list[TestEvent], mode: str = GPS_TRACK, language: str = "", routes: dict | None = None
) -> bytes:
    """The comparison PDF in ``language`` (default: comparison_language); ``routes``
    ({"leg": [ids], "case": [ids], "threshold": metres}) adds the routes section."""
    if len(events) < 2:
        raise ReportError(gettext_noop("A comparison needs at least two test events."))
    with fmt.written_in(language or comparison_language(events)):
        return _typeset(events, mode, routes)


def _typeset(events: list[TestEvent], mode: str, routes: dict | None) -> bytes:
    data = compare(events, mode)
    style.apply()
    reasons = {r.key: r for r in ItoReason.objects.all()}
    first = min(events, key=lambda e: (e.start, e.pk))
    with tempfile.TemporaryDirectory(prefix="ftt-compare-") as tmp:
        root = Path(tmp)
        growth = data["growth"]
        growth_chart(growth["points"], growth["total_distance"], growth["fit"], root / "growth.svg")
        hotspots = hotspot_chart(data["hotspots"], reasons, root / "hotspots.svg")
        names = {e.pk: _event_name(e) for e in events}
        document = {
            "text": comparison_text(),
            # Its one time, named like the event report's: the compared events' zones may differ.
            "generated": f"{fmt.timestamp(timezone.now(), first.tzinfo)} ({first.time_zone})",
            "events": [_row(names[e["id"]], e) for e in data["test_events"]],
            "versions": [_row(v["version"], v) for v in data["versions"]],
            "vehicles": [_row(v["name"], v) for v in data["vehicles"]],
            "growth": "growth.svg",
            "fit": growth["fit_rows"] or None,
            "hotspots": "hotspots.svg" if hotspots else None,
            "hotspot_note": _(
                "Take-overs at most %(radius)s m apart form one hotspot (single linkage); "
                "numbers as on the map."
            )
            % {"radius": fmt.number(data["hotspot_radius"])},
            "hotspot_rows": [_hotspot_row(spot, reasons, names) for spot in data["hotspots"]],
            "formulas": [[_(k), v] for k, v in data["formulas"].items()],
            "routes": routes_section(routes, root) if routes else None,
        }
        return typeset("compare.typ", document, root)
