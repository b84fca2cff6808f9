"""A PMTiles archive whose directory is a gzip bomb (a few kilobytes that unpack
to tens of megabytes) is refused at upload; a leaf directory that is one costs a
tile no more than the bound."""

import gzip
import tracemalloc

import pytest
from django.core.exceptions import ValidationError
from pmtiles.tile import Compression, Entry, TileType, serialize_directory, serialize_header

from basemaps.files import inspect_file
from basemaps.pmtiles_source import MAX_DIRECTORY_BYTES, DirectoryTooLarge, check_unpacked_size
from basemaps.services import layers


def bomb(path, root=None, leaf=b""):
    """An archive whose root directory is ``root`` (a gzip bomb unless given),
    followed by one leaf directory ``leaf``."""
    root = root or gzip.compress(bytes(MAX_DIRECTORY_BYTES + 1), compresslevel=9)
    end = 127 + len(root) + len(leaf)
    header = {
        "root_offset": 127,
        "root_length": len(root),
        "metadata_offset": end,
        "metadata_length": 0,
        "leaf_directory_offset": 127 + len(root),
        "leaf_directory_length": len(leaf),
        "tile_data_offset": end,
        "tile_data_length": 0,
        "addressed_tiles_count": 1,
        "tile_entries_count": 1,
        "tile_contents_count": 1,
        "clustered": True,
        "internal_compression": Compression.GZIP,
        "tile_compression": Compression.NONE,
        "tile_type": TileType.PNG,
        "min_zoom": 0,
        "max_zoom": 2,
        "min_lon_e7": 70_000_000,
        "min_lat_e7": 500_000_000,
        "max_lon_e7": 71_000_000,
        "max_lat_e7": 510_000_000,
        "center_zoom": 0,
        "center_lon_e7": 70_500_000,
        "center_lat_e7": 505_000_000,
    }
    path.write_bytes(serialize_header(header) + root + leaf)
    assert path.stat().st_size < MAX_DIRECTORY_BYTES // 100
    return path


def test_a_directory_that_unpacks_beyond_the_bound_is_refused_at_upload(tmp_path):
    with pytest.raises(ValidationError, match="gzip bomb"):
        inspect_file(bomb(tmp_path / "bomb.pmtiles"))


def test_a_bomb_behind_a_small_first_gzip_member_is_refused_too():
    # gzip.decompress unpacks the members one after the other.
    packed = gzip.compress(b"directory") + gzip.compress(bytes(MAX_DIRECTORY_BYTES))
    with pytest.raises(DirectoryTooLarge):
        check_unpacked_size(packed)
    check_unpacked_size(gzip.compress(b"a") + gzip.compress(bytes(MAX_DIRECTORY_BYTES - 1)))


def test_a_tile_under_a_leaf_directory_that_is_a_bomb_is_missing_within_the_bound(
    db, media_root, tmp_path, viewer_client
):
    # The upload reads the root; a leaf is unpacked when a tile under it is asked for.
    leaf = gzip.compress(bytes(MAX_DIRECTORY_BYTES * 8), compresslevel=9)
    root = serialize_directory([Entry(0, 0, len(leaf), 0)])
    path = bomb(tmp_path / "leaf.pmtiles", root=root, leaf=leaf)
    layer = layers.register_file(path, name="Leaf")
    tracemalloc.start()
    try:
        assert viewer_client.get(f"/tiles/{layer.key}/0/0/0.png").status_code == 404
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 2 * MAX_DIRECTORY_BYTES
