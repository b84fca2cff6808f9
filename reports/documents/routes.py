"""The comparison PDF's routes section: the routes overlaid on one map, the
stretches beyond the threshold in red, and per pair the figures of
``/api/reports/routes/`` (the same selector), formatted for the page."""

from pathlib import Path

from django.utils.translation import gettext as _
from django.utils.translation import gettext_noop

from reports import formatting as fmt
from reports.charts.maps import Line, MapPainter
from reports.documents.options import ReportError
from reports.selectors.routes import chosen_routes, compare_routes

# A, B, C, ... in the colours of the GUI's comparison page, and their names.
COLOURS = ("31,95,191", "224,123,0", "0,140,70", "130,60,170")
COLOUR_NAMES = (
    gettext_noop("blue"),
    gettext_noop("orange"),
    gettext_noop("green"),
    gettext_noop("purple"),
)
BEYOND = "208,0,0"


def routes_section(choice: dict, root: Path) -> dict:
    """Map, legend and figure rows for the routes of ``choice`` ({"leg": [ids],
    "case": [ids], "threshold": metres}); the map is drawn into ``root``."""
    try:
        routes = chosen_routes(choice["leg"], choice["case"])
        data = compare_routes(routes, choice["threshold"])
    except ValueError as exc:  # deleted since asked, or under two GPS points: say which
        raise ReportError(str(exc)) from None
    letters = {r.name: chr(ord("A") + i) for i, r in enumerate(routes)}
    lines = [
        Line(r.lon.tolist(), r.lat.tolist(), COLOURS[i % len(COLOURS)], width=3.5)
        for i, r in enumerate(routes)
    ]
    for pair in data["pairs"]:
        for side in pair["deviation"].values():
            for stretch in side["beyond"]:
                lon, lat = zip(*stretch, strict=True)
                lines.append(Line(list(lon), list(lat), BEYOND, width=1.5))
    drawn = MapPainter().gps_map(lines, str(root / "routes.png"))
    rows = []
    for pair in data["pairs"]:
        a, b = pair["routes"]
        frechet = fmt.metres(pair["frechet"])
        for name, other in ((a, b), (b, a)):
            side = pair["deviation"][name]
            rows.append(
                [_("%(a)s from %(b)s") % {"a": letters[name], "b": letters[other]}, frechet]
                + [fmt.metres(side[key]) for key in ("mean", "p95", "max")]
                + [fmt.percent(side["share_beyond"])]
            )
    return {
        "map": "routes.png",
        "note": drawn.note,
        "threshold": fmt.metres(data["threshold"]),
        "legend": [
            [letters[r.name], _(COLOUR_NAMES[i % len(COLOUR_NAMES)]), r.title]
            for i, r in enumerate(routes)
        ],
        "rows": rows,
    }
