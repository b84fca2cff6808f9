"""Import from a database of the original FTT, live and from its SQL dump.

The original database is built on the loopback PostgreSQL from
legacy_schema.sql (written for these tests from the feature inventory).
"""

import base64
import hashlib
import io
import os
import subprocess
from datetime import UTC, datetime
from pathlib import Path

import pytest
from django.conf import settings
from django.core.management import CommandError, call_command
from django.db import connection
from PIL import Image as PilImage

from events.models import ItoReason, Leg, Note, Segment, Shift, TestEvent
from exchange.importer import import_bundle
from exchange.legacy import DumpSource, LegacyBundle, LegacyError, PostgresSource
from telemetry.models import Image, LocalPose, MapImage, Pose
from tests.support import workers
from tests.support.field_day import jpeg
from tests.support.snapshot import snapshot

psycopg2 = pytest.importorskip("psycopg2")

HERE = Path(__file__).parent
# One per run and worker: the SpatiaLite and PostGIS runs may share the server at once.
LEGACY_DB = f"ftt_legacy_xchg_{connection.vendor}_{workers.INDEX}"


def _server() -> dict:
    """The PostgreSQL server of the test run; on SpatiaLite the loopback one."""
    db = settings.DATABASES["default"]
    if "postgis" in db["ENGINE"] or "postgresql" in db["ENGINE"]:
        return dict(
            host=db["HOST"] or "127.0.0.1",
            port=int(db["PORT"] or 5432),
            user=db["USER"],
            password=db["PASSWORD"],
        )
    return dict(host="127.0.0.1", port=5432, user="ftt", password="ftt")


SERVER = _server()
CONNINFO = " ".join(f"{k}={v}" for k, v in (SERVER | {"dbname": LEGACY_DB}).items())
T = 1554732764.0  # 2019-04-08 14:12:44 UTC, when the sample bag was recorded

pytestmark = pytest.mark.django_db


def _server_up() -> bool:
    try:
        psycopg2.connect(dbname="postgres", connect_timeout=3, **SERVER).close()
        return True
    except psycopg2.Error:
        return False


def _point(x, y, srid=4326):
    return f"ST_SetSRID(ST_MakePoint({x}, {y}), {srid})"


def _fill(cur, camera: bytes, map_jpeg: bytes):
    cur.execute(
        "INSERT INTO personnel VALUES (1, 'Jörg Müller', 'FKIE'), (2, 'Ann Lee', 'FKIE');"
        "INSERT INTO performer VALUES (1, 'FKIE');"
        "INSERT INTO vehicle VALUES (1, 'Husky', 'Husky A200', '', 'FKIE', 'arm');"
        "INSERT INTO pose_source VALUES (1, 'gps', 'GPS', '');"
    )
    cur.execute(
        "INSERT INTO test_event VALUES (1, %s, %s, 'Wachtberg', '2.1', '(UTC+01:00)', 'loop'),"
        " (2, %s, NULL, 'Wachtberg', '2.1', 'Europe/Berlin', '')",
        (T, T + 300, T + 86400),
    )
    # Shift numbers repeat after a delete in the original: 1, 1.
    cur.execute(
        "INSERT INTO shift VALUES"
        " (1, 1, %s, %s, 1, NULL, NULL, 2, 1, 'loop', 'yard', 1, '', 1),"
        " (2, 1, %s, %s, NULL, NULL, NULL, NULL, NULL, '', '', NULL, '', 1),"
        " (3, 2, %s, NULL, NULL, NULL, NULL, NULL, 1, '', '', 1, '', 1)",
        (T + 1, T + 200, T + 201, T + 300, T + 86401),
    )
    cur.execute(
        "INSERT INTO leg VALUES (1, 1, 1, %s, %s, 1, 1, NULL, 'leg note'),"
        " (2, 3, 1, %s, NULL, 2, 1, NULL, '')",
        (T + 2, T + 200, T + 86402),
    )
    cur.execute(
        f"""INSERT INTO segment VALUES
        (5, 1, NULL, NULL, 1, %s, %s, 'rock', 'dusk', '', 40.6,
            {_point(7.1290832, 50.6159943)}, {_point(1.5, -2.0, 0)}, %s),
        (6, 1, 5, 11, 1, %s, %s, '', '', 'steep', NULL,
            {_point(7.1290832, 50.6159943)}, NULL, %s),
        (7, 1, NULL, NULL, 2, %s, %s, '', '', '', NULL,
            {_point(7.1285435, 50.6161651)}, NULL, %s),
        (8, 1, NULL, NULL, 1, %s, %s, '', '', '', NULL, NULL, NULL, NULL),
        (9, 1, 8, 13, 1, %s, %s, 'pole', '', '', NULL, NULL, NULL, NULL),
        (10, 2, NULL, NULL, 1, %s, NULL, '', '', '', NULL, NULL, NULL, NULL),
        (11, 2, 10, 11, 1, %s, NULL, '', '', '', NULL, NULL, NULL, NULL)""",
        (
            T + 4, T + 50, T + 4.005,
            T + 4, T + 30, T + 4.005,
            T + 50, T + 88, T + 50.005,
            T + 88, T + 200,
            T + 88, T + 150,
            T + 86403,
            T + 86403,
        ),
    )  # fmt: skip
    cur.execute(
        f"""INSERT INTO pose VALUES
        (1, {_point(7.12908, 50.61599)}, %s, 5, 1, %s),
        (2, {_point(7.12907, 50.61600)}, %s, 6, 1, %s),
        (3, {_point(7.12854, 50.61616)}, %s, 7, 1, %s),
        (4, {_point(7.12806, 50.61614)}, %s, 8, NULL, NULL)""",
        (T + 6, T + 6.004, T + 8, T + 8.004, T + 52, T + 52.004, T + 90),
    )
    cur.execute(
        f"INSERT INTO local_pose VALUES (1, 7, %s, '/map', {_point(3.25, -1.5, 0)}, %s)",
        (T + 52, T + 52.01),
    )
    cur.execute(
        f"INSERT INTO map_image VALUES (1, 1, %s, 'map', 16, 12, 0.05,"
        f" {_point(-4.0, -3.0, 0)}, %s, %s)",
        (T + 60, base64.b64encode(map_jpeg), T + 59.9),
    )
    cur.execute(
        "INSERT INTO image VALUES (1, 8, 'front.jpg', %s, 'front camera', %s, %s)",
        (base64.b64encode(camera), T + 95, T + 94.9),
    )
    cur.execute("INSERT INTO note VALUES (1, 6, 'robot stopped at a rock', %s, 1)", (T + 20,))


@pytest.fixture(scope="module")
def original(tmp_path_factory):
    if not _server_up():
        pytest.skip(f"no PostgreSQL server on {SERVER['host']}:{SERVER['port']}")
    admin = psycopg2.connect(dbname="postgres", **SERVER)
    admin.autocommit = True
    with admin.cursor() as cur:
        cur.execute(f"DROP DATABASE IF EXISTS {LEGACY_DB} WITH (FORCE)")
        cur.execute(f"CREATE DATABASE {LEGACY_DB}")
    camera, map_jpeg = jpeg(40), jpeg(220)
    conn = psycopg2.connect(dbname=LEGACY_DB, **SERVER)
    with conn, conn.cursor() as cur:
        cur.execute((HERE / "legacy_schema.sql").read_text())
        _fill(cur, camera, map_jpeg)
    conn.close()
    dump = tmp_path_factory.mktemp("legacy") / "ftt_dump.sql"
    env = os.environ | {"PGPASSWORD": SERVER["password"]}
    subprocess.run(
        [
            "pg_dump",
            "-h",
            SERVER["host"],
            "-p",
            str(SERVER["port"]),
            "-U",
            SERVER["user"],
            "-d",
            LEGACY_DB,
            "-f",
            str(dump),
        ],
        check=True,
        env=env,
        timeout=120,
    )
    yield {"conninfo": CONNINFO, "dump": dump, "camera": camera}
    with admin.cursor() as cur:
        cur.execute(f"DROP DATABASE IF EXISTS {LEGACY_DB} WITH (FORCE)")
    admin.close()


def from_database():
    source = PostgresSource(CONNINFO)
    try:
        return LegacyBundle(source)
    finally:
        source.close()


def at(offset: float) -> datetime:
    return datetime.fromtimestamp(T + offset, tz=UTC)


def test_live_database_imports_hierarchy_telemetry_and_configuration(original, media_root):
    plan = import_bundle(from_database())
    assert plan.counts["test_events"]["added"] == 2
    first = TestEvent.objects.get(location="Wachtberg", end__isnull=False)
    assert (first.start, first.end) == (at(0), at(300))
    assert first.time_zone == "Etc/GMT-1"  # "(UTC+01:00)", one hour ahead of UTC
    shifts = list(Shift.objects.filter(test_event=first).order_by("start"))
    assert [s.number for s in shifts] == [1, 2]  # the repeated number became the next free
    assert shifts[0].vehicle.key == "husky"
    assert shifts[0].robot_operator.name == "Ann Lee"
    assert shifts[1].vehicle.key == "unknown-vehicle"
    assert Leg.objects.get(shift=shifts[0]).note == "leg note"

    masters = Segment.objects.filter(parent__isnull=True, leg__shift=shifts[0]).order_by("start")
    assert [m.segment_type_id for m in masters] == ["ito", "auto", "ito"]
    first_master = masters[0]
    assert (first_master.obstacle, first_master.ito_reason_id) == ("", None)
    child = first_master.children.get()
    # The master's annotation moved to its first child; the child's own text stays.
    assert (child.obstacle, child.lighting, child.slope) == ("rock", "dusk", "steep")
    assert child.ito_reason_id == "unassigned"
    assert first_master.start_position.coords == (7.1290832, 50.6159943)
    assert (first_master.start_local_x, first_master.start_local_y) == (1.5, -2.0)
    assert first_master.robot_stamp == at(4.005)
    assert ItoReason.objects.get(pk="battery").color == "9,9,9"
    assert masters[2].children.get().ito_reason_id == "battery"

    # A pose the original stored on the child belongs to its master.
    assert Pose.objects.filter(segment=first_master).count() == 2
    assert Pose.objects.count() == 4
    pose = Pose.objects.get(segment=masters[1])
    assert (pose.received, pose.robot_stamp) == (at(52), at(52.004))
    assert pose.pose_source.key == "gps"
    local = LocalPose.objects.get()
    assert (local.frame, local.x, local.y) == ("map", 3.25, -1.5)
    image = Image.objects.get()
    assert image.segment == masters[2] and image.description == "front camera"
    with image.image.open("rb") as handle:
        assert hashlib.sha256(handle.read()).digest() == hashlib.sha256(original["camera"]).digest()
    map_image = MapImage.objects.get()
    assert (map_image.origin_x, map_image.origin_y, map_image.resolution) == (-4.0, -3.0, 0.05)
    with map_image.image.open("rb") as handle, PilImage.open(io.BytesIO(handle.read())) as png:
        assert (png.format, png.size) == ("PNG", (16, 12))
    note = Note.objects.get()
    assert (note.segment, note.author.name, note.created) == (child, "Jörg Müller", at(20))

    # The original's open chain arrives open.
    open_shift = Shift.objects.get(end__isnull=True)
    assert open_shift.legs.get().segments.get(parent__isnull=True).end is None


def test_running_it_twice_adds_nothing(original, media_root):
    import_bundle(from_database())
    before = snapshot()
    plan = import_bundle(from_database())
    assert plan.changes() == 0
    assert snapshot() == before


def test_dump_file_gives_the_same_rows_as_the_live_database(original, media_root):
    call_command("ftt_import_legacy", str(original["dump"]), stdout=io.StringIO())
    from_dump = snapshot()
    assert len(from_dump["segments"]) == 7 and len(from_dump["poses"]) == 4
    # Same uids: reading the live database after its dump changes nothing.
    assert import_bundle(from_database()).changes() == 0
    assert snapshot() == from_dump


def test_the_import_s_own_changes_name_the_administrator_who_imported(
    original, media_root, role_user
):
    with pytest.raises(CommandError, match="no active administrator"):
        call_command("ftt_import_legacy", str(original["dump"]), by="nobody")
    admin = role_user("administrator")
    call_command(
        "ftt_import_legacy", str(original["dump"]), by=admin.username, stdout=io.StringIO()
    )
    entries = [e for model in (TestEvent, Segment) for e in model.history.all()]
    assert entries and {(e.history_channel, e.history_user) for e in entries} == {("import", admin)}
    assert {e.history_change_reason for e in entries} == {"archive import"}


def test_file_that_is_no_dump_is_refused(tmp_path):
    (tmp_path / "x.sql").write_text("SELECT 1;\n")
    with pytest.raises(LegacyError, match="not a plain pg_dump"):
        DumpSource(tmp_path / "x.sql")


def test_dry_run_prints_the_plan_and_stores_nothing(original, media_root):
    out = io.StringIO()
    call_command("ftt_import_legacy", str(original["dump"]), "--dry-run", stdout=out)
    assert "Would change" in out.getvalue()
    assert not TestEvent.objects.exists() and not list(media_root.rglob("*.*"))
