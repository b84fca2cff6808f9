"""The segments a search found, as a GeoJSON or CSV download."""

import io

from django.http import HttpResponse
from django.utils.translation import gettext as _
from rest_framework.exceptions import ValidationError

from common import geojson
from common.spreadsheet import SafeWriter
from events.selectors.found_segments import COLUMNS, MAX_FOUND

KINDS = ("geojson", "csv")


def found_file(rows: list[tuple], kind: str) -> HttpResponse:
    if kind not in KINDS:
        raise ValidationError(
            {"as": [(_("Choose one of: %(kinds)s.") % {"kinds": ", ".join(KINDS)})]}
        )
    if len(rows) > MAX_FOUND:
        message = _(
            "More than %(count)s segments found; narrow the search (area, time, vehicle)."
        ) % {"count": MAX_FOUND}
        raise ValidationError({"detail": [message]})
    if kind == "csv":
        return _csv(rows)
    return _geojson(rows)


def _geojson(rows) -> HttpResponse:
    properties = [(n, k) for n, k in enumerate(COLUMNS) if k not in ("id", "longitude", "latitude")]
    x, y = COLUMNS.index("longitude"), COLUMNS.index("latitude")
    features = (
        geojson.feature(
            None if row[x] is None else geojson.point([row[x], row[y]]),
            {k: _text(row[n]) for n, k in properties},
            id=row[0],
        )
        for row in rows
    )
    return _download(geojson.collection_text(features), "application/geo+json", "segments.geojson")


def _csv(rows) -> HttpResponse:
    out = io.StringIO()
    writer = SafeWriter(out)
    writer.writerow(COLUMNS)
    for row in rows:
        writer.writerow([_text(value) for value in row])
    return _download(out.getvalue(), "text/csv; charset=utf-8", "segments.csv")


def _text(value):
    return value.isoformat() if hasattr(value, "isoformat") else value


def _download(body: str, content_type: str, name: str) -> HttpResponse:
    response = HttpResponse(body, content_type=content_type)
    response["Content-Disposition"] = f'attachment; filename="{name}"'
    return response
