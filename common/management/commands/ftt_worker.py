"""``manage.py ftt_worker``: runs queued jobs (reports, archive imports).

django-tasks-db's worker loop, plus a heartbeat and the recovery of jobs a
dead worker left "running" (common.jobs). Stop it with SIGTERM or Ctrl-C: it
finishes the job at hand first; a second signal abandons the job, which the
next worker retries.
"""

import gc

from django_tasks_db.management.commands.db_worker import Command as DbWorkerCommand

from common import jobs


class Command(DbWorkerCommand):
    help = "Run FTT's background jobs (requested reports, archive imports)."

    def add_arguments(self, parser):
        super().add_arguments(parser)
        # Recognisable in the JobWorker table and in a failed job's reason.
        parser.set_defaults(worker_id=jobs.new_worker_id(), reload=False)

    def handle(self, *args, **options):
        worker_id = options["worker_id"]
        jobs.beat(worker_id)
        for task_id, outcome in jobs.recover_interrupted():
            self.stdout.write(f"job {task_id} of a stopped worker: {outcome}")
        heart = jobs.Heart(worker_id)
        heart.start()
        try:
            super().handle(*args, **options)
        finally:
            heart.stop()
            jobs.forget(worker_id)
            # The exit frees everything; the interpreter's last collection
            # would walk every loaded object first and delay Ctrl-C by seconds.
            gc.freeze()
