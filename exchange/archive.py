"""The FTT archive: one zip file that carries test events from one installation to another.

Layout::

    manifest.json          format name and version, the installation that wrote
                           it, what was selected, and the SHA-256 and size of
                           every other member
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
from django.utils.translation import gettext as _

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
            "installation": settings.FTT_INSTALLATION_NAME,
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
            raise ArchiveError(_("%(path)s does not exist or is not a file.") % {"path": self.path})
        try:
            self._zip = zipfile.ZipFile(self.path)
        except (zipfile.BadZipFile, OSError, ValueError) as exc:
            raise ArchiveError(
                _("%(archive)s is not an FTT archive (not a readable zip file: %(exc)s).")
                % {"archive": self.path.name, "exc": exc}
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
                _(
                    "%(archive)s has %(count)s members, more than the limit of "
                    "%(limit)s (FTT_ARCHIVE_MAX_MEMBERS)."
                )
                % {
                    "archive": self.path.name,
                    "count": len(infos),
                    "limit": settings.FTT_ARCHIVE_MAX_MEMBERS,
                }
            )
        total = sum(i.file_size for i in infos)
        if total > settings.FTT_ARCHIVE_MAX_TOTAL_BYTES:
            raise ArchiveError(
                _(
                    "%(archive)s unpacks to %(total)s bytes, more than the limit of "
                    "%(limit)s (FTT_ARCHIVE_MAX_TOTAL_BYTES)."
                )
                % {
                    "archive": self.path.name,
                    "total": total,
                    "limit": settings.FTT_ARCHIVE_MAX_TOTAL_BYTES,
                }
            )
        for info in infos:
            self._check_method(info)
            self._check_member(info.filename, info.file_size, info.compress_size)

    def _check_method(self, info: zipfile.ZipInfo) -> None:
        if info.flag_bits & _ENCRYPTED:
            raise ArchiveError(
                _("%(archive)s: %(member)s is encrypted; FTT reads unencrypted archives only.")
                % {"archive": self.path.name, "member": info.filename}
            )
        if info.compress_type not in _METHODS:
            raise ArchiveError(
                _(
                    "%(archive)s: %(member)s uses compression method "
                    "%(method)s; FTT reads stored, deflate, bzip2 and LZMA "
                    "members only."
                )
                % {
                    "archive": self.path.name,
                    "member": info.filename,
                    "method": info.compress_type,
                }
            )

    def _check_member(self, name: str, size: int, compressed: int) -> None:
        if size > settings.FTT_ARCHIVE_MAX_MEMBER_BYTES:
            raise ArchiveError(
                _(
                    "%(archive)s: %(name)s unpacks to more than the limit of "
                    "%(limit)s bytes "
                    "(FTT_ARCHIVE_MAX_MEMBER_BYTES)."
                )
                % {
                    "archive": self.path.name,
                    "name": name,
                    "limit": settings.FTT_ARCHIVE_MAX_MEMBER_BYTES,
                }
            )
        if size > _RATIO_FLOOR and size > settings.FTT_ARCHIVE_MAX_RATIO * max(compressed, 1):
            raise ArchiveError(
                _(
                    "%(archive)s: %(name)s is compressed more than "
                    "%(limit)s:1 (FTT_ARCHIVE_MAX_RATIO); refused as a "
                    "possible zip bomb."
                )
                % {
                    "archive": self.path.name,
                    "name": name,
                    "limit": settings.FTT_ARCHIVE_MAX_RATIO,
                }
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
                        raise ArchiveError(
                            _("%(archive)s is damaged at %(name)s.")
                            % {"archive": self.path.name, "name": name}
                        )
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
            raise ArchiveError(
                _("%(archive)s is damaged at %(name)s: %(exc)s")
                % {"archive": self.path.name, "name": name, "exc": exc}
            ) from None

    def _read_small(self, name: str, limit: int, what: str) -> bytes:
        if self._zip.getinfo(name).file_size > limit:
            raise ArchiveError(
                _("%(archive)s: %(what)s %(name)s is larger than %(limit)s bytes.")
                % {"archive": self.path.name, "what": what, "name": name, "limit": limit}
            )
        return b"".join(self._stream(name))

    def _read_manifest(self) -> dict:
        try:
            raw = self._read_small(MANIFEST, MAX_LINE, _("the manifest"))
        except KeyError:
            raise ArchiveError(
                _("%(archive)s is not an FTT archive: it has no %(manifest)s.")
                % {"archive": self.path.name, "manifest": MANIFEST}
            ) from None
        try:
            manifest = json.loads(raw)
        except (ValueError, RecursionError):
            raise ArchiveError(
                _("%(archive)s: %(manifest)s is not valid JSON.")
                % {"archive": self.path.name, "manifest": MANIFEST}
            ) from None
        if not isinstance(manifest, dict) or manifest.get("format") != FORMAT:
            raise ArchiveError(
                _("%(archive)s is not an FTT archive (its manifest names no '%(format)s' format).")
                % {"archive": self.path.name, "format": FORMAT}
            )
        version = manifest.get("version")
        if not isinstance(version, int) or version < 1:
            raise ArchiveError(
                _("%(archive)s: unknown archive format version %(version)s.")
                % {"archive": self.path.name, "version": f"{version!r}"}
            )
        if version > VERSION:
            raise ArchiveError(
                _(
                    "%(archive)s was written by a newer FTT (archive format "
                    "%(version)s); this installation reads up to format %(supported)s. "
                    "Update FTT first."
                )
                % {"archive": self.path.name, "version": version, "supported": VERSION}
            )
        members = manifest.get("members")
        if not isinstance(members, dict):
            raise ArchiveError(
                _("%(archive)s: the manifest lists no members.") % {"archive": self.path.name}
            )
        for name, entry in members.items():
            if not (
                isinstance(entry, dict)
                and isinstance(entry.get("sha256"), str)
                and isinstance(entry.get("size"), int)
            ):
                raise ArchiveError(
                    _("%(archive)s: the manifest entry of %(name)s needs a sha256 and a size.")
                    % {"archive": self.path.name, "name": name}
                )
        return manifest

    def _verify(self) -> None:
        listed = self.manifest["members"]
        present = {i.filename for i in self._zip.infolist() if not i.is_dir()}
        unsafe = [n for n in present | set(listed) if not _safe_name(n)]
        if unsafe:
            raise ArchiveError(
                _("%(archive)s contains unsafe member names: %(names)s.")
                % {"archive": self.path.name, "names": unsafe[:3]}
            )
        missing = sorted(set(listed) - present)
        if missing:
            raise ArchiveError(
                _("%(archive)s is incomplete: %(count)s member(s) missing, e.g. %(missing)s.")
                % {"archive": self.path.name, "count": len(missing), "missing": missing[0]}
            )
        extra = sorted(present - set(listed) - {MANIFEST})
        if extra:
            raise ArchiveError(
                _(
                    "%(archive)s contains member(s) its manifest does not list, e.g. "
                    "%(extra)s; it was changed after export."
                )
                % {"archive": self.path.name, "extra": extra[0]}
            )
        for name, expected in listed.items():
            digest = hashlib.sha256()
            size = 0
            for chunk in self._stream(name):
                digest.update(chunk)
                size += len(chunk)
            if digest.hexdigest() != expected["sha256"] or size != expected["size"]:
                raise ArchiveError(
                    _("%(archive)s is damaged: %(name)s does not match its checksum.")
                    % {"archive": self.path.name, "name": name}
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
                    raise ArchiveError(
                        _("%(name)s line %(number)s is longer than %(limit)s bytes.")
                        % {"name": name, "number": number, "limit": MAX_LINE}
                    )
                try:
                    record = json.loads(line)
                except (ValueError, RecursionError):
                    raise ArchiveError(
                        _("%(name)s line %(number)s is not valid JSON.")
                        % {"name": name, "number": number}
                    ) from None
                if not isinstance(record, dict):
                    raise ArchiveError(
                        _("%(name)s line %(number)s is not a JSON object.")
                        % {"name": name, "number": number}
                    )
                yield record

    def read_file(self, storage_name: str) -> bytes:
        """An image or map file; pictures are decoded whole anyway, and
        FTT_MAX_IMAGE_PIXELS bounds what they may be."""
        name = file_member(storage_name)
        if name not in self.manifest["members"]:
            raise ArchiveError(_("The archive lacks the file %(file)s.") % {"file": storage_name})
        return self._read_small(name, settings.FTT_ARCHIVE_MAX_FILE_BYTES, _("the file"))


def open_archive(path: str | os.PathLike) -> ArchiveReader:
    return ArchiveReader(path)
