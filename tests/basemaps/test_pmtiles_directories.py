"""A PMTiles archive whose directory is a gzip bomb (a few kilobytes that unpack
to tens of megabytes) is refused at upload."""

import gzip

import pytest
from django.core.exceptions import ValidationError
from pmtiles.tile import Compression, TileType, serialize_header

from basemaps.files import inspect_file
from basemaps.pmtiles_source import MAX_DIRECTORY_BYTES, DirectoryTooLarge, check_unpacked_size


def bomb(path):
    root = gzip.compress(bytes(MAX_DIRECTORY_BYTES + 1), compresslevel=9)
    header = {
        "root_offset": 127,
        "root_length": len(root),
        "metadata_offset": 127 + len(root),
        "metadata_length": 0,
        "leaf_directory_offset": 127 + len(root),
        "leaf_directory_length": 0,
        "tile_data_offset": 127 + len(root),
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
    path.write_bytes(serialize_header(header) + root)
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
