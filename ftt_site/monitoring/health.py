"""Liveness and readiness for a load balancer, systemd or Kubernetes.

Both answer without a session or a login: ``/healthz`` says the process serves
requests, ``/readyz`` says it can do its work (README, Monitoring).
"""

import shutil

from django.conf import settings
from django.db import DatabaseError, connection
from django.db.migrations.executor import MigrationExecutor
from django.http import JsonResponse
from django.views.decorators.cache import never_cache
from django.views.decorators.http import require_GET

from common import jobs

RETRY_AFTER_S = 10
# Migrations are only ever applied while a process runs, never taken back.
_migrated = False


@never_cache
@require_GET
def healthz(request):
    return JsonResponse({"status": "alive"})


@never_cache
@require_GET
def readyz(request):
    checks = {
        "database": _database(),
        "migrations": _migrations(),
        "job_worker": _job_worker(),
        "disk": _disk(),
    }
    ready = all(check["ok"] for check in checks.values())
    response = JsonResponse(
        {"status": "ready" if ready else "not ready", "checks": checks},
        status=200 if ready else 503,
    )
    if not ready:
        response["Retry-After"] = str(RETRY_AFTER_S)
    return response


def _database() -> dict:
    try:
        with connection.cursor() as cursor:
            cursor.execute("SELECT 1")
    except DatabaseError as exc:
        return {"ok": False, "detail": f"unreachable: {str(exc).strip()[:200]}"}
    return {"ok": True, "detail": connection.vendor}


def _migrations() -> dict:
    global _migrated
    if not _migrated:
        try:
            executor = MigrationExecutor(connection)
            missing = executor.migration_plan(executor.loader.graph.leaf_nodes())
        except DatabaseError:
            return {"ok": False, "detail": "cannot read the applied migrations"}
        if missing:
            return {"ok": False, "detail": f"{len(missing)} migrations not applied"}
        _migrated = True
    return {"ok": True, "detail": "all applied"}


def _job_worker() -> dict:
    try:
        alive = jobs.worker_running()
    except DatabaseError:
        return {"ok": False, "detail": "cannot read the workers' heartbeats"}
    if not alive:
        return {"ok": False, "detail": "no job worker beat recently; reports and imports wait"}
    return {"ok": True, "detail": "a job worker is alive"}


def _disk() -> dict:
    place = settings.MEDIA_ROOT
    while not place.exists():  # before the first upload; the disk is the parent's
        place = place.parent
    free_mb = shutil.disk_usage(place).free // (1024 * 1024)
    limit = settings.FTT_READY_MIN_FREE_MB
    if free_mb < limit:
        return {"ok": False, "detail": f"{free_mb} MB free under {limit} MB"}
    return {"ok": True, "detail": f"{free_mb} MB free"}
