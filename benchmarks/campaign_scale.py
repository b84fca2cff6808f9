"""Campaign scale: do the figures stay put while the pose tables grow?

Grows one throw-away PostGIS test database in steps (``--steps``, poses in
total) over a campaign of 100 test events, 1 000 shifts and 30 000 master
segments; the poses are bulk-loaded with COPY, appended to every segment's
track at each step.  At each step it prints:

- batch ingest poses/s into a live segment (store_poses, 1 000-pose batches);
- statistics of the whole campaign (every run of every test event, read at
  once as the comparison reads them) and of one test event, and the
  comparison with growth fit of the whole campaign;
- the PDF report of one test event (no map tiles; read back: it must be a PDF
  with a page per shift at least);
- the cockpit's segment list (its distances) and one leg's GPS tracks;
- database size per million poses, pose table and its indexes apart;

and the growth (seconds per 10x more poses) of each figure between steps.

    .venv/bin/python benchmarks/campaign_scale.py --steps 1000000,10000000 [--json out.json]

Side by side with another checkout (main as it was): run the script with
FTT_BENCH_ROOT naming that checkout's directory, then compare the two JSON
files with ``--compare a.json b.json``.  Where the checkout has per-segment
figures (telemetry.models.SegmentFigures) the loader fills them from the
generated tracks with the distance rule's own path_length, as the write path
would have; ``ftt_recount_figures --event`` checks one event against the poses.
"""

import argparse
import io
import json
import math
import os
import sys
import time
import uuid
from datetime import UTC, datetime, timedelta
from pathlib import Path

ROOT = Path(os.environ.get("FTT_BENCH_ROOT") or Path(__file__).resolve().parent.parent)
sys.path.insert(0, str(ROOT))
# Paths given on the command line are the caller's, not the checkout's.
CALLED_FROM = Path.cwd()
os.chdir(ROOT)
os.environ.setdefault("DJANGO_SETTINGS_MODULE", "ftt_site.settings")

import django  # noqa: E402

django.setup()

import numpy as np  # noqa: E402
from django.contrib.gis.geos import Point  # noqa: E402
from django.db import DatabaseError, connection  # noqa: E402

from events.models import Leg, Segment, Shift, TestEvent, Vehicle  # noqa: E402
from telemetry.models import Pose  # noqa: E402
from telemetry.selectors import distances  # noqa: E402
from telemetry.selectors.tracks import load_tracks  # noqa: E402
from telemetry.storage.keys import GPS_TRACK, LOCAL_TRACK  # noqa: E402

try:
    from telemetry.models import SegmentFigures
except ImportError:  # a checkout from before the figures
    SegmentFigures = None
try:
    from common.uid_sums import combined, uid_sum
except ImportError:  # a checkout whose figures keep no uid sum
    uid_sum = None
try:
    from telemetry.services.pose_partitions import ensure_partitions
except ImportError:  # a checkout with one pose table
    ensure_partitions = None

START = datetime(2025, 4, 1, 6, 0, tzinfo=UTC)
# A pose every 10 ms of a segment's hour, so a segment holds up to 360 000.
POSE_SECONDS = 0.01
STEP_DEG = 0.000005


def build(events: int, shifts: int, segments: int) -> list[int]:
    """The campaign's hierarchy, bulk-created; returns the master ids in track order."""
    vehicles = [
        Vehicle.objects.get_or_create(
            key=f"bench{i}", defaults={"short_description": f"Bench {i}"}
        )[0]
        for i in range(10)
    ]
    per_event, per_shift = shifts // events, segments // shifts
    hour = timedelta(hours=1)
    shift_hours = per_shift + 1
    event_rows = [
        TestEvent(location=f"Campaign {e}", start=START + e * per_event * shift_hours * hour,
                  end=START + (e + 1) * per_event * shift_hours * hour)
        for e in range(events)
    ]  # fmt: skip
    TestEvent.objects.bulk_create(event_rows)
    shift_rows = [
        Shift(test_event=event, vehicle=vehicles[s % 10], number=s + 1,
              start=event.start + s * shift_hours * hour,
              end=event.start + (s * shift_hours + per_shift) * hour)
        for event in event_rows
        for s in range(per_event)
    ]  # fmt: skip
    Shift.objects.bulk_create(shift_rows, batch_size=2000)
    legs = [
        Leg(shift=shift, number=1, start=shift.start, end=shift.end, weather_id="sunny")
        for shift in shift_rows
    ]
    Leg.objects.bulk_create(legs, batch_size=2000)
    masters = [
        Segment(
            leg=leg,
            segment_type_id="auto" if k % 2 == 0 else "ito",
            start=leg.start + k * hour,
            end=leg.start + (k + 1) * hour,
            start_position=Point(7.0 + n * 0.01 + k * 0.001, 50.0, srid=4326),
        )
        for n, leg in enumerate(legs)
        for k in range(per_shift)
    ]
    Segment.objects.bulk_create(masters, batch_size=5000)
    children = [
        Segment(leg_id=m.leg_id, parent=m, segment_type_id="ito", ito_reason_id="safety",
                start=m.start, end=m.end)
        for m in masters if m.segment_type_id == "ito"
    ]  # fmt: skip
    Segment.objects.bulk_create(children, batch_size=5000)
    return [m.pk for m in masters]


def _track(master: Segment, index: int, begin: int, end: int):
    """Points begin..end of the master's generated track (lon, lat, stamp)."""
    i = np.arange(begin, end)
    lon = master.start_position.x + STEP_DEG * i
    lat = 50.0 + 0.00002 * np.sin(i / 20.0 + index)
    return lon, lat, master.start.timestamp() + POSE_SECONDS * i


def grow(masters: list[Segment], have: int, want: int) -> float:
    """Append poses to every master until ``want`` in total; returns seconds."""
    started = time.perf_counter()
    per_now, per_next = have // len(masters), want // len(masters)
    if per_next <= per_now:  # a --resume at the size reached: measure again
        return 0.0
    table = Pose._meta.db_table
    columns = "uid, segment_id, point, robot_stamp, received, fix_status"
    added = {}
    with connection.cursor() as cursor:
        for begin in range(0, len(masters), 2000):
            out = io.StringIO()
            for index, m in enumerate(masters[begin : begin + 2000], start=begin):
                lon, lat, stamps = _track(m, index, per_now, per_next)
                uids = [uuid.uuid4() for _ in range(len(lon))]
                if uid_sum is not None:
                    added[m.pk] = uid_sum(uids)
                for uid, x, y, t in zip(
                    uids, lon.tolist(), lat.tolist(), stamps.tolist(), strict=True
                ):
                    stamp = datetime.fromtimestamp(t, UTC).isoformat()
                    point = f"SRID=4326;POINT({x!r} {y!r})"
                    out.write(f"{uid}\t{m.pk}\t{point}\t{stamp}\t{stamp}\t0\n")
            out.seek(0)
            with cursor.connection.cursor().copy(f"COPY {table} ({columns}) FROM STDIN") as copy:
                while chunk := out.read(1 << 20):
                    copy.write(chunk)
        cursor.execute(f"ANALYZE {table}")
    if SegmentFigures is not None:
        _add_to_figures(masters, per_next, added)
    return time.perf_counter() - started


def _add_to_figures(masters: list[Segment], per: int, added: dict[int, int]) -> None:
    """The figures the write path would have kept, from the generated tracks
    (``added``: the uid sum of each master's poses just loaded)."""
    stored_sums = (
        dict(SegmentFigures.objects.filter(mode=GPS_TRACK).values_list("segment_id", "uid_sum"))
        if uid_sum is not None
        else {}
    )
    rows = []
    for index, m in enumerate(masters):
        lon, lat, stamps = _track(m, index, 0, per)
        first, last = (
            datetime.fromtimestamp(stamps[0], UTC),
            datetime.fromtimestamp(stamps[-1], UTC),
        )
        rows.append(
            SegmentFigures(
                segment_id=m.pk, mode=GPS_TRACK, points=per,
                length=distances.path_length(lon, lat, GPS_TRACK),
                first_x=lon[0], first_y=lat[0], last_x=lon[-1], last_y=lat[-1],
                last_robot_stamp=last, last_received=last,
                last_id=None, first_stamp=first, last_stamp=last,
                min_x=lon.min(), min_y=lat.min(), max_x=lon.max(), max_y=lat.max(),
            )
        )  # fmt: skip
        if uid_sum is not None:
            rows[-1].uid_sum = combined(stored_sums.get(m.pk, 0), added[m.pk])
    fields = [
        f.name
        for f in SegmentFigures._meta.concrete_fields
        if f.name not in ("id", "segment", "mode")
    ]
    SegmentFigures.objects.bulk_create(
        rows, batch_size=2000, update_conflicts=True, unique_fields=["segment", "mode"],
        update_fields=fields,
    )  # fmt: skip
    # The last pose's id, as the write path keeps it (one statement for all).
    with connection.cursor() as cursor:
        cursor.execute(
            f"UPDATE {SegmentFigures._meta.db_table} f SET last_id = p.id FROM "
            f"(SELECT DISTINCT ON (segment_id) segment_id, id FROM {Pose._meta.db_table} "
            "ORDER BY segment_id, robot_stamp DESC, received DESC, id DESC) p "
            "WHERE f.segment_id = p.segment_id AND f.mode = 'gps'"
        )
        # The rows rewritten above leave a dead row each, which autovacuum
        # clears on a real server (it is off on the test cluster).
        cursor.execute(f"VACUUM ANALYZE {SegmentFigures._meta.db_table}")


def timed(func, repeat: int = 3) -> float:
    """Best of ``repeat`` wall seconds (the machine is shared)."""
    best = math.inf
    for _ in range(repeat):
        started = time.perf_counter()
        func()
        best = min(best, time.perf_counter() - started)
    return best


def ingest(batches: int = 10, size: int = 1000) -> float:
    """Poses/s of store_poses into a live segment of an open leg."""
    from events.services import logs, segments
    from events.services.segments import GpsPosition
    from telemetry.services.pose_writes import GpsFix, store_poses

    vehicle, _ = Vehicle.objects.get_or_create(key="live", defaults={"short_description": "Live"})
    event = TestEvent.objects.create(location="live", start=datetime.now(UTC) - timedelta(hours=1))
    shift = logs.create_shift(test_event=event, vehicle=vehicle)
    leg = logs.create_leg(shift=shift)
    master = segments.report_mode(leg, "auto", gps=GpsPosition(8.0, 50.0)).master
    total = 0
    started = time.perf_counter()
    for b in range(batches):
        fixes = [GpsFix(8.0 + (b * size + i) * 1e-6, 50.0) for i in range(size)]
        total += store_poses(master, fixes)
    seconds = time.perf_counter() - started
    return total / seconds


def one_leg(event: TestEvent) -> list[Segment]:
    """The masters of the test event's first leg, the leg whose list and tracks are timed."""
    leg = Leg.objects.filter(shift__test_event=event).order_by("pk").first()
    return list(Segment.objects.filter(leg=leg, parent=None).order_by("start", "id"))


def segment_list(leg_masters: list[Segment]) -> None:
    try:
        distances.displayed_distances(leg_masters)
    except TypeError:  # before the figures: the list measured the cached tracks
        from telemetry.selectors.cached_tracks import cached_tracks

        kept = cached_tracks(leg_masters)
        distances.displayed_distances(leg_masters, kept[GPS_TRACK], kept[LOCAL_TRACK])


def sizes() -> dict:
    # Summed over the table's partitions where it has them (a plain table is
    # its own one-row tree).
    with connection.cursor() as cursor:
        cursor.execute(
            "SELECT sum(pg_table_size(relid)), sum(pg_indexes_size(relid)),"
            " pg_database_size(current_database()) FROM"
            " (SELECT relid FROM pg_partition_tree(%s::regclass) UNION SELECT %s::regclass) t",
            [Pose._meta.db_table, Pose._meta.db_table],
        )
        row = [int(v) for v in cursor.fetchone()]
        return dict(zip(("pose table", "pose indexes", "database"), row, strict=True))


def one_pdf(event: TestEvent) -> None:
    """The event's PDF report, without map tiles, read back."""
    from pypdf import PdfReader

    from reports.documents.event_report import render_report
    from reports.documents.options import ReportOptions

    pdf = render_report(event, ReportOptions(no_tiles=True)).pdf
    pages = len(PdfReader(io.BytesIO(pdf)).pages)
    shifts = Shift.objects.filter(test_event=event).count()
    if pages < shifts:
        raise SystemExit(f"the report of {event} has {pages} pages for {shifts} shifts")


def measure(step: int) -> dict:
    from reports.selectors.comparison import compare
    from reports.selectors.statistics import campaign_runs, event_statistics, figures

    events = list(TestEvent.objects.exclude(location="live").order_by("start"))
    one = events[len(events) // 2]
    leg_masters = one_leg(one)

    def campaign_statistics():
        runs_of = campaign_runs(events, GPS_TRACK)
        return figures([run for e in events for run in runs_of[e.pk]])

    figures_now = {
        "ingest poses/s": ingest(),
        "statistics of the campaign s": timed(campaign_statistics),
        "statistics of one event s": timed(lambda: event_statistics(one, GPS_TRACK)),
        "comparison + growth, all events s": timed(lambda: compare(events, GPS_TRACK)),
        "PDF of one event s": timed(lambda: one_pdf(one), repeat=1),
        "segment list s": timed(lambda: segment_list(leg_masters)),
        "one leg's tracks s": timed(lambda: load_tracks([m.pk for m in leg_masters], GPS_TRACK)),
    }
    millions = step / 1e6
    figures_now.update({f"{k} MB per M poses": v / 1e6 / millions for k, v in sizes().items()})
    return figures_now


def report(steps: list[dict]) -> None:
    names = [k for k in steps[0] if k != "poses"]
    print(f"{'figure':40s}" + "".join(f"{s['poses']:>14,d}" for s in steps) + "   s per 10x")
    for name in names:
        values = [s[name] for s in steps]
        growth = ""
        if len(steps) > 1 and name.endswith(" s"):
            decades = math.log10(steps[-1]["poses"] / steps[0]["poses"])
            growth = f"{(values[-1] - values[0]) / decades:+.3f}"
        print(f"{name:40s}" + "".join(f"{v:14.3f}" for v in values) + f"   {growth}")


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--steps", default="1000000,10000000")
    parser.add_argument("--events", type=int, default=100)
    parser.add_argument("--shifts", type=int, default=1000)
    parser.add_argument("--segments", type=int, default=30000)
    parser.add_argument("--json", help="write the figures here")
    parser.add_argument(
        "--resume",
        action="store_true",
        help="go on growing the campaign a --keepdb run (or a failed one) left",
    )
    parser.add_argument(
        "--keepdb",
        action="store_true",
        help="use the test database a superuser made (empty, with PostGIS) and keep it",
    )
    parser.add_argument("--compare", nargs=2, metavar="JSON", help="print two runs side by side")
    args = parser.parse_args()
    if args.compare:
        for path in args.compare:
            print(f"== {path}")
            report(json.loads((CALLED_FROM / path).read_text()))
        return
    if connection.vendor != "postgresql":
        sys.exit("campaign_scale needs PostGIS (FTT_DATABASE_URL)")
    print(f"checkout {ROOT}; load average {' '.join(f'{v:.2f}' for v in os.getloadavg())}")
    old_name = connection.settings_dict["NAME"]
    connection.creation.create_test_db(
        verbosity=0, autoclobber=True, serialize=False, keepdb=args.keepdb or args.resume
    )
    run(args)
    if args.keepdb or args.resume:
        return
    try:
        connection.creation.destroy_test_db(old_name, verbosity=0)
    except DatabaseError as exc:
        # The change feed's waker may still hold a session; the next run clobbers it.
        print(f"test database kept: {exc}".splitlines()[0])


def run(args) -> None:
    started = time.perf_counter()
    campaign = Segment.objects.filter(parent=None).exclude(leg__shift__test_event__location="live")
    if not args.resume:
        build(args.events, args.shifts, args.segments)
    masters = list(campaign.order_by("pk"))
    if ensure_partitions is not None:
        # The months of the campaign, made before its poses arrive (as the
        # daily job would have, had the campaign been recorded live).
        ensure_partitions(min(m.start for m in masters), max(m.end for m in masters))
    print(f"campaign of {len(masters)} masters built in {time.perf_counter() - started:.1f} s")
    have = Pose.objects.filter(segment__in=campaign).count() if args.resume else 0
    steps = []
    for want in (int(float(s)) for s in args.steps.split(",")):
        seconds = grow(masters, have, want)
        have = want
        print(f"{want:,d} poses loaded ({seconds:.1f} s); measuring", flush=True)
        steps.append({"poses": want, "load": os.getloadavg()[0], **measure(want)})
        report(steps)
        if args.json:
            (CALLED_FROM / args.json).write_text(json.dumps(steps, indent=1))


if __name__ == "__main__":
    main()
