"""GeoJSON as FTT writes it (RFC 7946): the one place that spells its objects.

Every GeoJSON answer and download (the tracks API, the test event's tracks
export, a search's found segments) builds its geometries, features and
collection here. A collection is written either as one object
(`collection`, `collection_text`) or piece by piece (`COLLECTION_HEAD`,
`feature_text` between `SEPARATOR`s, `COLLECTION_TAIL`), and both give the
same text as ``json.dumps`` of the whole.
"""

import json
from collections.abc import Iterable, Iterator

# json.dumps's default separators, so pieces joined equal the whole dumped.
SEPARATOR = ", "
COLLECTION_HEAD = '{"type": "FeatureCollection", "features": ['
COLLECTION_TAIL = "]}"

_NO_ID = object()


def point(coordinates) -> dict:
    return {"type": "Point", "coordinates": coordinates}


def line(coordinates) -> dict:
    return {"type": "LineString", "coordinates": coordinates}


def path(coordinates: list) -> dict:
    """A driven path: a line, or a point when it has a single position."""
    return line(coordinates) if len(coordinates) > 1 else point(coordinates[0])


def feature(geometry: dict | None, properties: dict, *, id=_NO_ID) -> dict:
    """A feature; ``id`` is left out unless given, ``geometry`` None is one without a place."""
    body = {"type": "Feature"}
    if id is not _NO_ID:
        body["id"] = id
    body["geometry"] = geometry
    body["properties"] = properties
    return body


def collection(features: list[dict]) -> dict:
    return {"type": "FeatureCollection", "features": features}


def feature_text(one: dict) -> str:
    return json.dumps(one, ensure_ascii=False)


def collection_chunks(features: Iterable[dict]) -> Iterator[str]:
    """The collection's text in pieces: the head, each feature, the tail."""
    yield COLLECTION_HEAD
    for n, one in enumerate(features):
        yield feature_text(one) if n == 0 else SEPARATOR + feature_text(one)
    yield COLLECTION_TAIL


def collection_text(features: Iterable[dict]) -> str:
    return "".join(collection_chunks(features))
