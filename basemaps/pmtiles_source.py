"""The bytes of a PMTiles archive as pmtiles' Reader reads them, with every
directory's unpacked size bounded: the library gunzips a directory whole, so a
small directory that unpacks to gigabytes (a gzip bomb) would cost each tile
that much memory and time."""

import mmap
import zlib

from pmtiles.tile import deserialize_header

# Far above what a directory of the largest real archives unpacks to (the
# specification keeps the root under 16 KiB and leaves under a few megabytes).
MAX_DIRECTORY_BYTES = 32 * 1024 * 1024
_PIECE = 1024 * 1024


class DirectoryTooLarge(ValueError):
    """A directory of the archive unpacks to more than MAX_DIRECTORY_BYTES."""


def check_unpacked_size(packed: bytes, limit: int = MAX_DIRECTORY_BYTES) -> None:
    """Refuse (DirectoryTooLarge) gzip data that unpacks to more than ``limit``
    bytes, unpacking no more than that."""
    # gzip.decompress, as the library calls it, unpacks every member of the
    # stream one after the other, so the bound counts them all together; the
    # unpacked bytes are counted a piece at a time and not kept.
    left = limit
    while packed:
        unpacker = zlib.decompressobj(wbits=31)
        while not unpacker.eof:
            try:
                piece = unpacker.decompress(packed, _PIECE)
            except zlib.error:
                return  # not gzip: the library says so itself
            left -= len(piece)
            if left < 0:
                raise DirectoryTooLarge(limit)
            if not piece and len(unpacker.unconsumed_tail) == len(packed):
                return  # cut short: the library says so itself
            packed = unpacker.unconsumed_tail
        packed = unpacker.unused_data


def bounded_source(handle):
    """get_bytes for pmtiles' Reader over an open file: a read of the root or a
    leaf directory is refused when it unpacks beyond MAX_DIRECTORY_BYTES."""
    mapping = mmap.mmap(handle.fileno(), 0, access=mmap.ACCESS_READ)
    header = deserialize_header(mapping[0:127])
    root = header["root_offset"]
    leaves = (
        header["leaf_directory_offset"],
        header["leaf_directory_offset"] + header["leaf_directory_length"],
    )

    def get_bytes(offset: int, length: int) -> bytes:
        data = mapping[offset : offset + length]
        if offset == root or leaves[0] <= offset < leaves[1]:
            check_unpacked_size(data)
        return data

    return get_bytes
