"""The FTT archive: one zip file that carries test events from one installation to another.

Layout::

    manifest.json          format name and version, what was selected, and the
                           SHA-256 and size of every other member
    data/<table>.jsonl     one JSON object per line, see exchange.records
    files/<storage name>   image and map files, named as in media storage

Nothing is trusted before every member listed in the manifest has been read
and its checksum compared, and members the manifest does not list are refused:
a truncated copy from a USB stick or a zip from somewhere else is turned away
before the database is touched.
"""

import hashlib
import json
import os
import tempfile
import zipfile
import zlib
from collections.abc import Iterator
from datetime import UTC, datetime
from pathlib import Path, PurePosixPath

from django.conf import settings

FORMAT = "ftt-archive"
# Raised only when an older FTT would misread an archive.  Added tables and
# fields keep it: an older FTT passes over them, and this one reads an older
# archive's missing ones as their defaults (docs/data-exchange.md).
VERSION = 1
MANIFEST = "manifest.json"
CHUNK = 1024 * 1024

# Manifest and record lines are parsed whole, so they get their own bound.
MAX_LINE = 16 * 1024 * 1024
# Below this size a high compression ratio is harmless (a JSONL member of
# repeated field names compresses 50:1 and more).
_RATIO_FLOOR = 16 * 1024 * 1024

# Files that are already compressed gain nothing from deflate.
_STORED_SUFFIXES = {".png", ".jpg", ".jpeg", ".webp", ".gif"}


class ArchiveError(Exception):
    """The file is not an FTT archive this installation can read, or it is damaged."""


def data_member(table: str) -> str:
    return f"data/{table}.jsonl"


def file_member(storage_name: str) -> str:
    return f"files/{storage_name}"


class ArchiveWriter:
    """Writes to a temporary file next to the target and renames it on success,
    so an interrupted export never leaves a half archive under the final name."""

    def __init__(self, path: str | os.PathLike, *, selection: dict, format: str = FORMAT):
        self.path = Path(path)
        self.selection = selection
        self.format = format
        self.members: dict[str, dict] = {}
        self.counts: dict[str, int] = {}
        fd, self._tmp = tempfile.mkstemp(
            prefix=".ftt-export-", suffix=".zip", dir=self.path.parent or "."
        )
        os.close(fd)
        self._zip = zipfile.ZipFile(self._tmp, "w", zipfile.ZIP_DEFLATED, allowZip64=True)

    def __enter__(self):
        return self

    def __exit__(self, exc_type, exc, tb):
        if exc_type is None:
            self.close()
        else:
            self._zip.close()
            os.unlink(self._tmp)
        return False

    def write_records(self, table: str, records) -> int:
        name = data_member(table)
        digest = hashlib.sha256()
        size = count = 0
        with self._zip.open(name, "w", force_zip64=True) as member:
            for record in records:
                line = (json.dumps(record, ensure_ascii=False, sort_keys=True) + "\n").encode()
                digest.update(line)
                size += len(line)
                count += 1
                member.write(line)
        self.members[name] = {"sha256": digest.hexdigest(), "size": size}
        self.counts[table] = count
        return count

    def write_file(self, storage_name: str, source) -> None:
        """Copy an open binary file object into the archive under files/."""
        self.write_member(file_member(storage_name), source)

    def write_member(self, name: str, source) -> None:
        if name in self.members:
            return
        compress = (
            zipfile.ZIP_STORED
            if PurePosixPath(name).suffix.lower() in _STORED_SUFFIXES
            else zipfile.ZIP_DEFLATED
        )
        info = zipfile.ZipInfo(name, date_time=datetime.now(UTC).timetuple()[:6])
        info.compress_type = compress
        digest = hashlib.sha256()
        size = 0
        with self._zip.open(info, "w", force_zip64=True) as member:
            while chunk := source.read(CHUNK):
                digest.update(chunk)
                size += len(chunk)
                member.write(chunk)
        self.members[name] = {"sha256": digest.hexdigest(), "size": size}

    def close(self) -> dict:
        manifest = {
            "format": self.format,
            "version": VERSION,
            "created": datetime.now(UTC).isoformat(),
            "selection": self.selection,
            "counts": self.counts,
            "members": self.members,
        }
        self._zip.writestr(MANIFEST, json.dumps(manifest, indent=1, sort_keys=True))
        self._zip.close()
        os.replace(self._tmp, self.path)
        self.manifest = manifest
        return manifest


def _safe_name(name: str) -> bool:
    path = PurePosixPath(name)
    return not path.is_absolute() and ".." not in path.parts and "\\" not in name


# General purpose flag bit 0: the member is encrypted.
_ENCRYPTED = 0x1
_METHODS = (zipfile.ZIP_STORED, zipfile.ZIP_DEFLATED, zipfile.ZIP_BZIP2, zipfile.ZIP_LZMA)


class ArchiveReader:
    """A verified archive.  Open it with :func:`open_archive`.

    Every member is streamed within the limits of the FTT_ARCHIVE_* settings
    (member count, member size, total size, compression ratio), so a zip bomb is
    refused after reading at most the limit, never decompressed whole."""

    def __init__(self, path: str | os.PathLike):
        self.path = Path(path)
        if not self.path.is_file():
            raise ArchiveError(f"{self.path} does not exist or is not a file.")
        try:
            self._zip = zipfile.ZipFile(self.path)
        except (zipfile.BadZipFile, OSError, ValueError) as exc:
            raise ArchiveError(
                f"{self.path.name} is not an FTT archive (not a readable zip file: {exc})."
            ) from None
        try:
            self._check_sizes()
            self.manifest = self._read_manifest()
            self._verify()
        except BaseException:
            self._zip.close()
            raise

    def close(self):
        self._zip.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False

    def _check_sizes(self) -> None:
        """What the zip directory declares; _stream holds each member to it."""
        infos = [i for i in self._zip.infolist() if not i.is_dir()]
        if len(infos) > settings.FTT_ARCHIVE_MAX_MEMBERS:
            raise ArchiveError(
                f"{self.path.name} has {len(infos)} members, more than the limit of "
                f"{settings.FTT_ARCHIVE_MAX_MEMBERS} (FTT_ARCHIVE_MAX_MEMBERS)."
            )
        total = sum(i.file_size for i in infos)
        if total > settings.FTT_ARCHIVE_MAX_TOTAL_BYTES:
            raise ArchiveError(
                f"{self.path.name} unpacks to {total} bytes, more than the limit of "
                f"{settings.FTT_ARCHIVE_MAX_TOTAL_BYTES} (FTT_ARCHIVE_MAX_TOTAL_BYTES)."
            )
        for info in infos:
            self._check_method(info)
            self._check_member(info.filename, info.file_size, info.compress_size)

    def _check_method(self, info: zipfile.ZipInfo) -> None:
        if info.flag_bits & _ENCRYPTED:
            raise ArchiveError(
                f"{self.path.name}: {info.filename} is encrypted; "
                "FTT reads unencrypted archives only."
            )
        if info.compress_type not in _METHODS:
            raise ArchiveError(
                f"{self.path.name}: {info.filename} uses compression method "
                f"{info.compress_type}; FTT reads stored, deflate, bzip2 and LZMA members only."
            )

    def _check_member(self, name: str, size: int, compressed: int) -> None:
        if size > settings.FTT_ARCHIVE_MAX_MEMBER_BYTES:
            raise ArchiveError(
                f"{self.path.name}: {name} unpacks to more than the limit of "
                f"{settings.FTT_ARCHIVE_MAX_MEMBER_BYTES} bytes (FTT_ARCHIVE_MAX_MEMBER_BYTES)."
            )
        if size > _RATIO_FLOOR and size > settings.FTT_ARCHIVE_MAX_RATIO * max(compressed, 1):
            raise ArchiveError(
                f"{self.path.name}: {name} is compressed more than "
                f"{settings.FTT_ARCHIVE_MAX_RATIO}:1 (FTT_ARCHIVE_MAX_RATIO); "
                f"refused as a possible zip bomb."
            )

    def _stream(self, name: str) -> Iterator[bytes]:
        """The member in chunks, refused as soon as it outgrows its declared size."""
        info = self._zip.getinfo(name)
        size = 0
        try:
            with self._zip.open(info) as member:
                while chunk := member.read(CHUNK):
                    size += len(chunk)
                    if size > info.file_size:
                        raise ArchiveError(f"{self.path.name} is damaged at {name}.")
                    self._check_member(name, size, info.compress_size)
                    yield chunk
        except (
            zipfile.BadZipFile,
            OSError,
            EOFError,
            zlib.error,
            ValueError,
            NotImplementedError,
            RuntimeError,
        ) as exc:
            raise ArchiveError(f"{self.path.name} is damaged at {name}: {exc}") from None

    def _read_small(self, name: str, limit: int, what: str) -> bytes:
        if self._zip.getinfo(name).file_size > limit:
            raise ArchiveError(f"{self.path.name}: {what} {name} is larger than {limit} bytes.")
        return b"".join(self._stream(name))

    def _read_manifest(self) -> dict:
        try:
            raw = self._read_small(MANIFEST, MAX_LINE, "the manifest")
        except KeyError:
            raise ArchiveError(
                f"{self.path.name} is not an FTT archive: it has no {MANIFEST}."
            ) from None
        try:
            manifest = json.loads(raw)
        except (ValueError, RecursionError):
            raise ArchiveError(f"{self.path.name}: {MANIFEST} is not valid JSON.") from None
        if not isinstance(manifest, dict) or manifest.get("format") != FORMAT:
            raise ArchiveError(
                f"{self.path.name} is not an FTT archive (its manifest names no '{FORMAT}' format)."
            )
        version = manifest.get("version")
        if not isinstance(version, int) or version < 1:
            raise ArchiveError(f"{self.path.name}: unknown archive format version {version!r}.")
        if version > VERSION:
            raise ArchiveError(
                f"{self.path.name} was written by a newer FTT (archive format {version}); "
                f"this installation reads up to format {VERSION}. Update FTT first."
            )
        members = manifest.get("members")
        if not isinstance(members, dict):
            raise ArchiveError(f"{self.path.name}: the manifest lists no members.")
        for name, entry in members.items():
            if not (
                isinstance(entry, dict)
                and isinstance(entry.get("sha256"), str)
                and isinstance(entry.get("size"), int)
            ):
                raise ArchiveError(
                    f"{self.path.name}: the manifest entry of {name} needs a sha256 and a size."
                )
        return manifest

    def _verify(self) -> None:
        listed = self.manifest["members"]
        present = {i.filename for i in self._zip.infolist() if not i.is_dir()}
        unsafe = [n for n in present | set(listed) if not _safe_name(n)]
        if unsafe:
            raise ArchiveError(f"{self.path.name} contains unsafe member names: {unsafe[:3]}.")
        missing = sorted(set(listed) - present)
        if missing:
            raise ArchiveError(
                f"{self.path.name} is incomplete: {len(missing)} member(s) missing, "
                f"e.g. {missing[0]}."
            )
        extra = sorted(present - set(listed) - {MANIFEST})
        if extra:
            raise ArchiveError(
                f"{self.path.name} contains member(s) its manifest does not list, "
                f"e.g. {extra[0]}; it was changed after export."
            )
        for name, expected in listed.items():
            digest = hashlib.sha256()
            size = 0
            for chunk in self._stream(name):
                digest.update(chunk)
                size += len(chunk)
            if digest.hexdigest() != expected["sha256"] or size != expected["size"]:
                raise ArchiveError(
                    f"{self.path.name} is damaged: {name} does not match its checksum."
                )

    def records(self, table: str) -> Iterator[dict]:
        name = data_member(table)
        if name not in self.manifest["members"]:
            return
        with self._zip.open(name) as member:
            number = 0
            while line := member.readline(MAX_LINE + 1):
                number += 1
                if len(line) > MAX_LINE:
                    raise ArchiveError(f"{name} line {number} is longer than {MAX_LINE} bytes.")
                try:
                    record = json.loads(line)
                except (ValueError, RecursionError):
                    raise ArchiveError(f"{name} line {number} is not valid JSON.") from None
                if not isinstance(record, dict):
                    raise ArchiveError(f"{name} line {number} is not a JSON object.")
                yield record

    def read_file(self, storage_name: str) -> bytes:
        """An image or map file; pictures are decoded whole anyway, and
        FTT_MAX_IMAGE_PIXELS bounds what they may be."""
        name = file_member(storage_name)
        if name not in self.manifest["members"]:
            raise ArchiveError(f"The archive lacks the file {storage_name}.")
        return self._read_small(name, settings.FTT_ARCHIVE_MAX_FILE_BYTES, "the file")


def open_archive(path: str | os.PathLike) -> ArchiveReader:
    return ArchiveReader(path)
