"""The FTT archive: one zip file that carries test events from one installation to another.

Layout::

    manifest.json          format name and version, what was selected, and the
                           SHA-256 and size of every other member
    data/<table>.jsonl     one JSON object per line, see events.exchange.records
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

FORMAT = "ftt-archive"
VERSION = 1
MANIFEST = "manifest.json"
CHUNK = 1024 * 1024

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


class ArchiveReader:
    """A verified archive.  Open it with :func:`open_archive`."""

    def __init__(self, path: str | os.PathLike):
        self.path = Path(path)
        if not self.path.is_file():
            raise ArchiveError(f"{self.path} does not exist or is not a file.")
        try:
            self._zip = zipfile.ZipFile(self.path)
        except (zipfile.BadZipFile, OSError) as exc:
            raise ArchiveError(
                f"{self.path.name} is not an FTT archive (not a readable zip file: {exc})."
            ) from None
        try:
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

    def _read_manifest(self) -> dict:
        try:
            raw = self._zip.read(MANIFEST)
        except KeyError:
            raise ArchiveError(
                f"{self.path.name} is not an FTT archive: it has no {MANIFEST}."
            ) from None
        except (zipfile.BadZipFile, OSError, EOFError) as exc:
            raise ArchiveError(f"{self.path.name} is damaged: {exc}") from None
        try:
            manifest = json.loads(raw)
        except ValueError:
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
        if not isinstance(manifest.get("members"), dict):
            raise ArchiveError(f"{self.path.name}: the manifest lists no members.")
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
            try:
                with self._zip.open(name) as member:
                    while chunk := member.read(CHUNK):
                        digest.update(chunk)
                        size += len(chunk)
            except (zipfile.BadZipFile, OSError, EOFError, zlib.error) as exc:
                raise ArchiveError(f"{self.path.name} is damaged at {name}: {exc}") from None
            if digest.hexdigest() != expected.get("sha256") or size != expected.get("size"):
                raise ArchiveError(
                    f"{self.path.name} is damaged: {name} does not match its checksum."
                )

    def records(self, table: str) -> Iterator[dict]:
        name = data_member(table)
        if name not in self.manifest["members"]:
            return
        with self._zip.open(name) as member:
            for number, line in enumerate(member, start=1):
                try:
                    record = json.loads(line)
                except ValueError:
                    raise ArchiveError(f"{name} line {number} is not valid JSON.") from None
                if not isinstance(record, dict):
                    raise ArchiveError(f"{name} line {number} is not a JSON object.")
                yield record

    def read_file(self, storage_name: str) -> bytes:
        name = file_member(storage_name)
        if name not in self.manifest["members"]:
            raise ArchiveError(f"The archive lacks the file {storage_name}.")
        return self._zip.read(name)


def open_archive(path: str | os.PathLike) -> ArchiveReader:
    return ArchiveReader(path)
