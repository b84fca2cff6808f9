"""One GeoJSON builder: every answer and download spells its objects through common/geojson.py."""

import ast
import json
from pathlib import Path

import pytest

from common import geojson

ROOT = Path(__file__).resolve().parents[2]
GEOJSON_TYPES = {
    "Feature",
    "FeatureCollection",
    "Point",
    "LineString",
    "Polygon",
    "MultiPoint",
    "MultiLineString",
    "MultiPolygon",
    "GeometryCollection",
}


def _features():
    return [
        geojson.feature(geojson.path([[7.0, 50.0], [7.1, 50.1]]), {"label": "Leg 1 · #1"}, id=3),
        geojson.feature(geojson.path([[7.2, 50.2]]), {"label": "Straße"}),
        geojson.feature(None, {"label": None}, id=4),
    ]


@pytest.mark.parametrize("count", [0, 1, 3])
def test_the_collection_in_pieces_is_the_collection_dumped_whole(count):
    features = _features()[:count]
    whole = json.dumps(geojson.collection(features), ensure_ascii=False)
    assert geojson.collection_text(features) == whole
    assert "".join(geojson.collection_chunks(iter(features))) == whole
    assert json.loads(whole)["type"] == "FeatureCollection"


def test_a_path_of_one_position_is_a_point_and_an_id_only_when_given():
    one, two, placeless = _features()
    assert one == {
        "type": "Feature",
        "id": 3,
        "geometry": {"type": "LineString", "coordinates": [[7.0, 50.0], [7.1, 50.1]]},
        "properties": {"label": "Leg 1 · #1"},
    }
    assert "id" not in two and two["geometry"] == {"type": "Point", "coordinates": [7.2, 50.2]}
    assert placeless["geometry"] is None


def _built_geojson(path: Path):
    """Dict displays whose "type" is a GeoJSON type: a GeoJSON object built by hand."""
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Dict):
            for key, value in zip(node.keys, node.values, strict=True):
                if (
                    isinstance(key, ast.Constant)
                    and key.value == "type"
                    and isinstance(value, ast.Constant)
                    and value.value in GEOJSON_TYPES
                ):
                    yield f"{path.relative_to(ROOT)}:{node.lineno}"


def test_no_module_but_the_builder_builds_geojson():
    packages = [p.parent for p in ROOT.glob("*/__init__.py") if p.parent.name != "tests"]
    found = [
        site
        for package in packages
        for path in sorted(package.rglob("*.py"))
        if path != ROOT / "common" / "geojson.py"
        for site in _built_geojson(path)
    ]
    assert found == [], "GeoJSON built outside common/geojson.py"
