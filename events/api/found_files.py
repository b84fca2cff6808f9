"""The segments a search found, as a GeoJSON or CSV download (streamed:
common.api.downloads)."""

import itertools
from collections.abc import Iterator

from django.http import StreamingHttpResponse
from django.utils.translation import gettext as _
from rest_framework.exceptions import ValidationError

from common import geojson
from common.api.downloads import streamed_download
from common.spreadsheet import csv_rows
from events.selectors.found_segments import COLUMNS, MAX_FOUND

KINDS = ("geojson", "csv")


def found_file(request, rows: list[tuple], kind: str) -> StreamingHttpResponse:
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
        return streamed_download(request, _csv(rows), "text/csv; charset=utf-8", "segments.csv")
    return streamed_download(request, _geojson(rows), "application/geo+json", "segments.geojson")


def _geojson(rows) -> Iterator[str]:
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
    return geojson.collection_chunks(features)


def _csv(rows) -> Iterator[str]:
    yield from csv_rows(itertools.chain([COLUMNS], ([_text(v) for v in row] for row in rows)))


def _text(value):
    return value.isoformat() if hasattr(value, "isoformat") else value
