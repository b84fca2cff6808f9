"""Where did it fail, at scale: the place search over many take-overs.

Bulk-creates N take-overs (ITO masters with one reason each, default 100 000)
spread over 100 test events and a 20 km square, in a throw-away test database
of the configured backend (FTT_DATABASE_URL for PostGIS, else SpatiaLite), then
times through the API, as a viewer:
  * GET /api/segments/?master=true&mode=ito&within=<polygon> (first page),
  * the same with reason= and a date range,
  * GET /api/segments/found/?…&as=geojson for every take-over in the area,
  * GET /api/segments/?in_bbox=… across the antimeridian (an empty result).
Target (issue 29): each within 300 ms at 100 000 take-overs.

    FTT_DATABASE_URL=postgis://... .venv/bin/python benchmarks/place_search.py [--take-overs N]
        [--repeat R] [--keepdb]
"""

import argparse
import json
import os
import statistics
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

import numpy as np  # noqa: E402
from django.contrib.gis.geos import Point  # noqa: E402
from django.db import connection  # noqa: E402
from django.test import Client  # noqa: E402
from django.test.utils import setup_test_environment  # noqa: E402

from common import roles  # noqa: E402
from events.models import Leg, Segment, SegmentType, Shift, TestEvent, Vehicle  # noqa: E402

TARGET_S = 0.3
T0 = datetime(2026, 4, 1, 8, 0, tzinfo=UTC)
REASONS = ("safety", "planner", "unexpected", "other")


def build(take_overs: int) -> None:
    rng = np.random.default_rng(7)
    vehicle = Vehicle.objects.create(key="bench-search", short_description="search bench")
    events = [
        TestEvent.objects.create(location=f"search bench {i}", start=T0 + timedelta(days=i))
        for i in range(100)
    ]
    shifts = Shift.objects.bulk_create(
        Shift(
            test_event=e, vehicle=vehicle, number=1, start=e.start, end=e.start + timedelta(hours=8)
        )
        for e in events
    )
    legs = Leg.objects.bulk_create(Leg(shift=s, number=1, start=s.start, end=s.end) for s in shifts)
    per_leg = take_overs // len(legs)
    lon = 7.0 + rng.random(take_overs) * 0.28
    lat = 50.5 + rng.random(take_overs) * 0.18
    masters = []
    for i, leg in enumerate(legs):
        for j in range(per_leg):
            k = i * per_leg + j
            at = leg.start + timedelta(seconds=10 * j)
            masters.append(
                Segment(
                    leg=leg,
                    segment_type_id=SegmentType.ITO,
                    start=at,
                    end=at + timedelta(seconds=5),
                    start_position=Point(float(lon[k]), float(lat[k]), srid=4326),
                    uid=uuid.uuid4(),
                )
            )
    masters = Segment.objects.bulk_create(masters, batch_size=5000)
    Segment.objects.bulk_create(
        (
            Segment(
                leg_id=m.leg_id,
                parent=m,
                segment_type_id=SegmentType.ITO,
                ito_reason_id=REASONS[n % len(REASONS)],
                start=m.start,
                end=m.end,
                start_position=m.start_position,
                uid=uuid.uuid4(),
            )
            for n, m in enumerate(masters)
        ),
        batch_size=5000,
    )
    # Planner statistics and visibility map as autovacuum keeps them on a live
    # database: right after a bulk load the planner would take the table for a
    # handful of rows and could not answer from an index alone.
    with connection.cursor() as cursor:
        cursor.execute("VACUUM ANALYZE" if connection.vendor == "postgresql" else "ANALYZE")


def viewer() -> Client:
    from django.contrib.auth import get_user_model
    from django.contrib.auth.models import Group
    from rest_framework.authtoken.models import Token

    user, _ = get_user_model().objects.get_or_create(username="bench-viewer")
    user.groups.add(Group.objects.get(name=roles.VIEWER))
    token, _ = Token.objects.get_or_create(user=user)
    return Client(HTTP_AUTHORIZATION=f"Token {token.key}")


def timed(client, path, query, repeat) -> tuple[float, int]:
    times, size = [], 0
    client.get(path, query)  # the first request of a process sets up what every one needs
    for _ in range(repeat):
        started = time.perf_counter()
        response = client.get(path, query)
        times.append(time.perf_counter() - started)
        assert response.status_code == 200, response.content[:300]
        size = len(response.content)
    return statistics.median(times), size


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--take-overs", type=int, default=100_000)
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument(
        "--keepdb",
        action="store_true",
        help="keep the test database afterwards and reuse one built before (any --take-overs)",
    )
    args = parser.parse_args()
    setup_test_environment()  # the test client's host is allowed
    old_name = connection.creation.create_test_db(
        verbosity=0, autoclobber=True, serialize=False, keepdb=args.keepdb
    )
    try:
        started = time.perf_counter()
        if not Vehicle.objects.filter(key="bench-search").exists():
            build(args.take_overs)
        masters = Segment.objects.masters().count()
        print(
            f"load average {' '.join(f'{v:.2f}' for v in os.getloadavg())}; backend "
            f"{connection.vendor}: {masters} take-overs in 100 test events "
            f"(ready in {time.perf_counter() - started:.1f} s)"
        )
        client = viewer()
        # About 1 % of the square: a site's corner where something keeps happening.
        area = {
            "type": "Polygon",
            "coordinates": [[[7.0, 50.5], [7.03, 50.5], [7.03, 50.52], [7.0, 50.52], [7.0, 50.5]]],
        }
        base = {"master": "true", "mode": "ito", "within": json.dumps(area)}
        cases = [
            ("list, within a polygon", "/api/segments/", base),
            (
                "list, + reason and dates",
                "/api/segments/",
                {**base, "reason": "safety", "start_after": (T0 + timedelta(days=50)).isoformat()},
            ),
            ("every one found, GeoJSON", "/api/segments/found/", base),
            (
                "box across ±180°",
                "/api/segments/",
                {"master": "true", "in_bbox": "179,-10,-179,10"},
            ),
        ]
        print(f"{'query':<30} {'median':>9} {'bytes':>10} {'target':>8}")
        for name, path, query in cases:
            seconds, size = timed(client, path, query, args.repeat)
            verdict = "ok" if seconds <= TARGET_S else "over"
            target = f"{TARGET_S * 1000:5.0f} ms {verdict}"
            print(f"{name:<30} {seconds * 1000:7.0f} ms {size:>10} {target}")
    finally:
        connection.creation.destroy_test_db(old_name, verbosity=0, keepdb=args.keepdb)


if __name__ == "__main__":
    main()
