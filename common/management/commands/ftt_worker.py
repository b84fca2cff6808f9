"""``manage.py ftt_worker``: runs queued jobs (reports, archive imports), the
pose tables' daily upkeep (``manage.py ftt_pose_storage``) and, with a
directory, its role checks every ``FTT_LDAP_RECHECK_SECONDS``
(``manage.py ftt_directory_recheck``).

django-tasks-db's worker loop, plus a heartbeat and the recovery of jobs a
dead worker left "running" (common.jobs). Stop it with SIGTERM or Ctrl-C: it
finishes the job at hand first; a second signal abandons the job, which the
next worker retries.
"""

import gc
import logging
import threading

from django.conf import settings
from django.core.management import call_command
from django.db import connection
from django.utils.translation import gettext as _
from django_tasks_db.management.commands.db_worker import Command as DbWorkerCommand

from common import jobs
from common.apps import DIRECTORY_BACKEND

log = logging.getLogger(__name__)

# The pose tables' upkeep (partitions, retention) runs at the start and then daily.
UPKEEP_EVERY_S = 24 * 3600


class Upkeep(threading.Thread):
    """Runs a command beside the job loop, at the start and then every ``every_s``."""

    def __init__(self, command: str, every_s: float):
        super().__init__(name=f"ftt-upkeep-{command}", daemon=True)
        self.command = command
        self.every_s = every_s
        self.stopped = threading.Event()

    def run(self) -> None:
        try:
            while True:
                try:
                    call_command(self.command)
                except Exception:  # another worker's upkeep, a busy database: next time
                    log.exception("upkeep: %s", self.command)
                if self.stopped.wait(self.every_s):
                    return
        finally:
            connection.close()


class Command(DbWorkerCommand):
    help = _("Run FTT's background jobs (requested reports, archive imports).")

    def add_arguments(self, parser):
        super().add_arguments(parser)
        # Recognisable in the JobWorker table and in a failed job's reason.
        parser.set_defaults(worker_id=jobs.new_worker_id(), reload=False)

    def handle(self, *args, **options):
        worker_id = options["worker_id"]
        jobs.beat(worker_id)
        for task_id, outcome in jobs.recover_interrupted():
            self.stdout.write(
                _("job %(id)s of a stopped worker: %(outcome)s")
                % {
                    "id": task_id,
                    "outcome": _("queued again") if outcome == "retried" else _("failed"),
                }
            )
        heart = jobs.Heart(worker_id)
        heart.start()
        upkeeps = [Upkeep("ftt_pose_storage", UPKEEP_EVERY_S)]
        if DIRECTORY_BACKEND in settings.AUTHENTICATION_BACKENDS:
            upkeeps.append(Upkeep("ftt_directory_recheck", settings.FTT_LDAP_RECHECK_SECONDS))
        for upkeep in upkeeps:
            upkeep.start()
        try:
            super().handle(*args, **options)
        finally:
            heart.stop()
            for upkeep in upkeeps:
                upkeep.stopped.set()
            jobs.forget(worker_id)
            # The exit frees everything; the interpreter's last collection
            # would walk every loaded object first and delay Ctrl-C by seconds.
            gc.freeze()
