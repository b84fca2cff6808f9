"""Importing an archive that arrived as an upload (API or GUI form).

A dry run answers at once. A real import is first tried as a dry run in the
request, so a damaged or conflicting archive is refused with its reason right
away, then queued as a job (common/jobs.py): the upload is kept in
``FTT_DATA_DIR/job_files`` until ``manage.py ftt_worker`` has imported it. The
import is one transaction, so a worker killed mid-import leaves nothing half
done, and the job is simply run again (then failed with the reason).
"""

import shutil
import tempfile
import uuid
from pathlib import Path

from django.conf import settings
from django.db import transaction
from django.utils import timezone
from django.utils.translation import gettext_noop
from django_tasks import task

from common import jobs
from common.deferred_text import DeferredText, deferred, deferred_fields
from exchange.archive import open_archive
from exchange.importer import Plan, import_bundle
from exchange.models import ArchiveImport


def import_upload(upload, *, dry_run: bool, by=None) -> Plan:
    """Raises ArchiveError (not an FTT archive, damaged) or ImportRefused
    (conflicts with data here); in both cases nothing was written."""
    # The archive reader needs a seekable file on disk, not an upload stream.
    with tempfile.NamedTemporaryFile(suffix=".zip") as copy:
        _copy(upload, copy)
        return import_file(Path(copy.name), dry_run=dry_run, by=by)


def import_file(path: Path, *, dry_run: bool, by=None) -> Plan:
    """``by``: the account the import's own changes are recorded as made by."""
    with open_archive(str(path)) as bundle:
        return import_bundle(bundle, dry_run=dry_run, by=_signed_in(by))


def _signed_in(user):
    return user if user is not None and user.is_authenticated else None


def queue_import(upload, *, user=None) -> tuple[ArchiveImport, Plan]:
    """Check the upload (dry run) and queue its import; returns the job and the preview.

    Raises what :func:`import_upload` raises, and then queues nothing.
    """
    folder = Path(settings.DATA_DIR) / "job_files"
    folder.mkdir(mode=0o700, parents=True, exist_ok=True)
    upload_copy = folder / f"import-{uuid.uuid4().hex}.zip"
    try:
        with open(upload_copy, "wb") as copy:
            _copy(upload, copy)
        preview = import_file(upload_copy, dry_run=True, by=user)
        with transaction.atomic():
            job = ArchiveImport.objects.create(
                filename=(getattr(upload, "name", "") or upload_copy.name)[:255],
                path=str(upload_copy.resolve()),
                **deferred_fields("message", jobs.waiting()),
                **deferred_fields("verdict", preview.verdict_text(), 200),
                requested_by=_signed_in(user),
            )
            import_archive.enqueue(job.pk)
    except BaseException:
        upload_copy.unlink(missing_ok=True)
        raise
    return job, preview


def _copy(upload, target) -> None:
    if hasattr(upload, "chunks"):
        for chunk in upload.chunks():
            target.write(chunk)
    else:
        shutil.copyfileobj(upload, target)
    target.flush()


@task()
def import_archive(job_id: int) -> str:
    """The queued job: import a kept upload, record the outcome, delete the file."""
    job = ArchiveImport.objects.get(pk=job_id)
    if job.is_finished:
        return job.status
    ArchiveImport.objects.filter(pk=job_id).update(
        status=ArchiveImport.Status.RUNNING,
        **deferred_fields("message", deferred(gettext_noop("importing"))),
    )
    try:
        plan = import_file(Path(job.path), dry_run=False, by=job.requested_by)
    except Exception as exc:  # refused, malformed or a file gone: the reason is the outcome
        _finish(job, ArchiveImport.Status.FAILED, **deferred_fields("error", _reason(exc)))
        return ArchiveImport.Status.FAILED
    _finish(
        job,
        ArchiveImport.Status.DONE,
        **deferred_fields("verdict", plan.verdict_text(), 200),
        changes=plan.changes(),
        counts={table: dict(counts) for table, counts in plan.counts.items()},
        lines=plan.lines(),
    )
    return ArchiveImport.Status.DONE


@jobs.when_interrupted(import_archive)
def _worker_stopped(job_id: int, *, retried: bool, reason: DeferredText) -> None:
    if retried:
        again = deferred(gettext_noop("queued again: %(reason)s"), reason=reason)
        ArchiveImport.objects.filter(pk=job_id).update(
            status=ArchiveImport.Status.QUEUED, **deferred_fields("message", again, 200)
        )
        return
    job = ArchiveImport.objects.filter(pk=job_id).first()
    if job is not None:
        nothing = deferred(gettext_noop("%(reason)s Nothing was imported."), reason=reason)
        _finish(job, ArchiveImport.Status.FAILED, **deferred_fields("error", nothing))


def _reason(exc: Exception) -> str:
    """Why an import failed; an archive's refusal is in the language of the worker
    (FTT_LANGUAGE), said where it was found, with the record it names."""
    return str(exc) or exc.__class__.__name__


FINISHED = {
    ArchiveImport.Status.DONE: gettext_noop("done"),
    ArchiveImport.Status.FAILED: gettext_noop("failed"),
}


def _finish(job: ArchiveImport, status: str, **fields) -> None:
    if job.path:
        Path(job.path).unlink(missing_ok=True)
    ArchiveImport.objects.filter(pk=job.pk).update(
        status=status,
        **deferred_fields("message", deferred(FINISHED[status])),
        path="",
        finished=timezone.now(),
        **fields,
    )
