"""Importing an archive that arrived as an upload (API or GUI form)."""

import tempfile

from exchange.archive import open_archive
from exchange.importer import Plan, import_bundle


def import_upload(upload, *, dry_run: bool) -> Plan:
    """Raises ArchiveError (not an FTT archive, damaged) or ImportRefused
    (conflicts with data here); in both cases nothing was written."""
    # The archive reader needs a seekable file on disk, not an upload stream.
    with tempfile.NamedTemporaryFile(suffix=".zip") as copy:
        for chunk in upload.chunks():
            copy.write(chunk)
        copy.flush()
        with open_archive(copy.name) as bundle:
            return import_bundle(bundle, dry_run=dry_run)
