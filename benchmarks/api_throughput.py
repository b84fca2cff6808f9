"""How fast the REST API serves tracks and takes pose batches, on the configured database.

Builds a throw-away test event with one leg of N GPS poses (default 100 000) over
20 master segments, then times:
  * GET /api/tracks/?leg=ID (one LineString per master),
  * GET /api/poses/?leg=ID&page_size=5000 (one page of rows),
  * POST /api/poses/batch/ with 1000 new poses, and the same batch again (all known).
Everything is deleted afterwards. Prints seconds and rates.

    FTT_DATABASE_URL=postgis://... .venv/bin/python benchmarks/api_throughput.py [--poses N]
"""

import argparse
import os
import sys
import time
import uuid
from datetime import UTC, datetime, timedelta
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
os.environ.setdefault("DJANGO_SETTINGS_MODULE", "ftt_site.settings")

import django  # noqa: E402

django.setup()

from django.contrib.auth import get_user_model  # noqa: E402
from django.contrib.auth.models import Group  # noqa: E402
from rest_framework.test import APIClient  # noqa: E402

from events.models import Vehicle  # noqa: E402
from events.services import deletion, logs, segments  # noqa: E402
from telemetry.services import recording  # noqa: E402
from telemetry.services.recording import GpsFix  # noqa: E402

SEGMENTS = 20


def timed(label, func, rows=None):
    start = time.perf_counter()
    result = func()
    seconds = time.perf_counter() - start
    rate = f", {rows / seconds:,.0f} rows/s" if rows else ""
    print(f"{label:<48} {seconds:8.3f} s{rate}")
    return result


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--poses", type=int, default=100_000)
    n = parser.parse_args().poses
    t0 = datetime(2026, 1, 5, 8, tzinfo=UTC)
    vehicle, _ = Vehicle.objects.get_or_create(key="bench-api", short_description="bench")
    user, _ = get_user_model().objects.get_or_create(username="bench-api-operator")
    user.groups.add(Group.objects.get(name="operator"))
    event = logs.create_test_event(at=t0, location="api benchmark")
    try:
        shift = logs.create_shift(test_event=event, vehicle=vehicle, at=t0)
        leg = logs.create_leg(shift=shift, at=t0)
        per = n // SEGMENTS

        def build():
            for s in range(SEGMENTS):
                at = t0 + timedelta(seconds=1 + s * per)
                master = segments.report_mode(leg, ("auto", "ito")[s % 2], at=at).master
                fixes = [
                    GpsFix(7.0 + i * 1e-6, 50.0 + s * 1e-3, robot_stamp=at + timedelta(seconds=i))
                    for i in range(per)
                ]
                recording.record_poses(master, fixes)
            return master

        master = timed(f"build {n:,} poses via services", build, n)
        client = APIClient(HTTP_HOST="localhost")
        client.force_authenticate(user)
        # The first request imports every view module (reports pull in matplotlib); not timed.
        client.get("/api/tracks/")

        tracks = timed(
            "GET /api/tracks/?leg", lambda: client.get("/api/tracks/", {"leg": leg.pk}), n
        )
        assert tracks.status_code == 200 and len(tracks.json()["features"]) == SEGMENTS
        print(f"{'  response size':<48} {len(tracks.content) / 1e6:8.2f} MB")
        page = timed(
            "GET /api/poses/?leg&page_size=5000",
            lambda: client.get("/api/poses/", {"leg": leg.pk, "page_size": 5000}),
            5000,
        )
        assert page.status_code == 200
        batch = {
            "segment": master.pk,
            "poses": [
                {"uid": str(uuid.uuid4()), "longitude": 8.0, "latitude": 50.0 + i * 1e-6}
                for i in range(1000)
            ],
        }
        post = lambda: client.post("/api/poses/batch/", batch, format="json")  # noqa: E731
        first = timed("POST /api/poses/batch/ (1000 new)", post, 1000)
        again = timed("POST /api/poses/batch/ (1000 known)", post, 1000)
        assert first.json() == {"stored": 1000} and again.json() == {"stored": 0}
    finally:
        timed("delete the test event", lambda: deletion.delete(event))
        user.delete()


if __name__ == "__main__":
    main()
