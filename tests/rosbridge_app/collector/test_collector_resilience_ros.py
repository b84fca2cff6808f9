"""Nothing is lost: SIGKILL and restart, a database that goes away, hostile input."""

import os
import re
import signal
import subprocess
import sys
import threading
import time
from datetime import UTC, datetime

import numpy as np
import pytest

from events.models import Segment
from rosbridge_app.models import Collector
from telemetry.models import Image, MapImage, Pose
from tests.support.ros import ROOT, fastdds_clean, requires_ros, wait_for

pytestmark = [pytest.mark.ros, requires_ros]
EVERY_FIX = {"params.pose_min_distance": 0.0, "params.pose_min_period": 0.0}
# Fixes per second in the outage drill: over 100 of them in the outage take a few seconds.
OUTAGE_RATE = 20.0


class Drive(threading.Thread):
    """Publishes the mode twice a second and a GPS fix at ``rate`` Hz, each fix at a
    new place (10 cm apart), until stopped.  ``self.mode`` may be changed on the fly."""

    def __init__(self, ros, rate=10.0):
        from sensor_msgs.msg import NavSatFix
        from std_msgs.msg import Bool

        super().__init__(daemon=True)
        self.NavSatFix, self.Bool = NavSatFix, Bool
        self.fix = ros.publisher(NavSatFix, "/gps_fix", 100)
        self.mode_pub = ros.publisher(Bool, "/robot_mode")
        ros.wait_subscribed(self.fix, 60)  # a collector starts slowly on a busy machine
        ros.wait_subscribed(self.mode_pub)
        self.rate, self.mode, self.sent = rate, True, []
        self.halt = threading.Event()

    def run(self):
        i, next_mode = 0, 0.0
        while not self.halt.is_set():
            now = time.time()
            if now >= next_mode:
                self.mode_pub.publish(self.Bool(data=self.mode))
                next_mode = now + 0.5
            f = self.NavSatFix(latitude=50.0 + i * 1e-6, longitude=7.0)
            f.status.status = 0
            f.header.stamp.sec, f.header.stamp.nanosec = int(now), int((now % 1) * 1e9)
            self.fix.publish(f)
            self.sent.append((now, f.latitude))
            i += 1
            time.sleep(1.0 / self.rate)

    def stop(self):
        self.halt.set()
        self.join(5)


def test_sigkill_and_restart_continue_the_segment_without_duplicates(
    ros, start_collector, robot_leg
):
    collector = start_collector(params=EVERY_FIX, args=["--start-logging"])
    drive = Drive(ros)
    drive.start()
    wait_for(lambda: Pose.objects.count() > 20, what="poses before the kill")
    collector.stop(signal.SIGKILL)
    fastdds_clean()
    killed_at = time.time()
    time.sleep(1.0)
    # No --start-logging: the collector resumes the state it had.
    start_collector()
    wait_for(
        lambda: Pose.objects.filter(robot_stamp__gt=_aware(killed_at + 2)).count() > 10,
        what="poses after the restart",
    )
    drive.stop()
    _written(time.time())
    masters = list(Segment.objects.filter(leg=robot_leg, parent__isnull=True))
    assert len(masters) == 1 and masters[0].segment_type_id == "auto" and masters[0].end is None
    latitudes = list(Pose.objects.values_list("point", flat=True))
    assert len({p.y for p in latitudes}) == len(latitudes)  # every fix at most once
    assert Collector.objects.get(name="collector").logging


def test_ten_sigkills_during_a_drive_each_restart_hears_within_10_s_and_stores_every_fix_once(
    ros, start_collector, robot_leg
):
    collector = start_collector(params=EVERY_FIX, args=["--start-logging"])
    drive = Drive(ros)
    drive.start()
    try:
        wait_for(lambda: Pose.objects.count() > 10, 60, what="poses before the first kill")
        for kill in range(1, 11):
            collector.stop(signal.SIGKILL)
            # No fastdds_clean(): whatever a SIGKILL leaves behind stays, as on a robot.
            collector = start_collector()  # back once it has beaten
            ready = _aware(time.time())
            wait_for(
                lambda ready=ready: Pose.objects.filter(robot_stamp__gt=ready).exists(),
                10,
                0.2,
                f"a fix stored within 10 s of restart {kill}",
            )
            # It logs on for a moment before the next kill.
            wait_for(
                lambda ready=ready: Pose.objects.filter(robot_stamp__gt=ready).count() >= 5,
                30,
                0.2,
                f"more fixes after restart {kill}",
            )
    finally:
        drive.stop()
    _written(time.time())
    latitudes = [p.y for p in Pose.objects.values_list("point", flat=True)]
    assert len(set(latitudes)) == len(latitudes), "a fix was stored twice"
    sent = {round(lat, 7) for _, lat in drive.sent}
    assert {round(lat, 7) for lat in latitudes} <= sent, "a stored fix was never sent"
    masters = list(Segment.objects.filter(leg=robot_leg, parent__isnull=True))
    assert len(masters) == 1 and masters[0].end is None


def test_a_collector_that_hears_nothing_while_the_robot_publishes_recovers_by_itself(
    ros, start_collector, robot_leg
):
    from rclpy.qos import qos_profile_sensor_data
    from sensor_msgs.msg import NavSatFix

    from rosbridge_app.collector.deaf_watch import DEAF

    collector = start_collector(
        params={**EVERY_FIX, "params.deaf_timeout": 3.0, "params.sensor_reliable": True},
        args=["--start-logging"],
    )
    pid = collector.popen.pid
    # A best-effort GPS never matches the collector's reliable subscription: the
    # ROS graph shows the publisher, and nothing arrives; a deaf collector.
    unheard = ros.publisher(NavSatFix, "/gps_fix", qos_profile_sensor_data)
    heard = None
    halt = threading.Event()

    def publish():
        i = 0
        while not halt.is_set():
            i += 1
            for pub in (unheard, heard):
                if pub is not None:
                    pub.publish(NavSatFix(latitude=50.0 + i * 1e-6, longitude=7.0))
            time.sleep(0.1)

    publisher = threading.Thread(target=publish, daemon=True)
    publisher.start()
    try:
        record = wait_for(
            lambda: Collector.objects.filter(name="collector", hearing__contains=DEAF).first(),
            40,
            0.3,
            "the collector to say it hears nothing",
        )
        assert "/gps_fix" in record.hearing and "subscriptions re-created" in record.hearing
        # Re-created subscriptions do not help here, so it renews itself in place.
        wait_for(lambda: "renewing the collector" in collector.output(), 40, 0.3, "a renewal")
        renewed = wait_for(
            lambda: Collector.objects.filter(
                name="collector", started__gt=record.started, stopped=None
            ).first(),
            60,
            0.3,
            "the renewed collector's heartbeat",
        )
        assert collector.alive() and collector.popen.pid == pid == renewed.pid
        assert renewed.logging  # it resumed what it was doing
        heard = ros.publisher(NavSatFix, "/gps_fix", 10)
        wait_for(
            lambda: (
                Collector.objects.filter(name="collector", hearing="")
                .exclude(inputs__gps_fix__count=0)
                .exists()
            ),
            40,
            0.3,
            "the collector to hear the GPS again",
        )
        # Deaf again after a renewal, it does not restart in a loop.
        assert collector.output().count("renewing the collector") == 1
    finally:
        halt.set()
        publisher.join(5)


def test_sigterm_stores_everything_received_before_exiting(ros, start_collector, robot_leg):
    collector = start_collector(params=EVERY_FIX, args=["--start-logging"])
    drive = Drive(ros, rate=150.0)

    def segment_opened():
        drive.mode_pub.publish(drive.Bool(data=True))
        return Segment.objects.filter(leg=robot_leg).exists()

    # Fixes sent before the collector has a segment have nowhere to go; under
    # load that window is long, so the drive starts once the segment exists.
    wait_for(segment_opened, interval=0.3, what="the first segment")
    drive.start()
    time.sleep(3.0)
    drive.stop()
    time.sleep(0.2)  # the last fixes reach the collector; most are not written yet
    assert collector.stop(signal.SIGTERM) == 0
    record = Collector.objects.get(name="collector")
    received = record.inputs["gps_fix"]["count"]  # the final heartbeat's count
    assert received >= 0.9 * len(drive.sent)
    assert Pose.objects.count() == received
    assert record.stopped is not None
    assert "everything written" in collector.output()


def _written(stopped_at):
    """Waits until a heartbeat after the drive stopped (and its last fixes reached
    the collector) says nothing is pending: every fix received is written."""
    wait_for(
        lambda: Collector.objects.filter(
            name="collector", pending=0, last_seen__gt=_aware(stopped_at + 1)
        ).exists(),
        30,
        0.2,
        "a heartbeat with nothing pending",
    )


def _aware(t):
    from datetime import UTC, datetime

    return datetime.fromtimestamp(t, tz=UTC)


def test_hostile_input_is_survived(ros, start_collector, robot_leg):
    from nav_msgs.msg import OccupancyGrid
    from sensor_msgs.msg import Image as RosImage
    from sensor_msgs.msg import NavSatFix
    from std_msgs.msg import Bool

    # RELIABLE: a 25 MB frame sent best-effort is usually lost in fragments.
    collector = start_collector(
        args=["--start-logging"],
        params={"params.image_buffer_size": 1, "params.sensor_reliable": True},
    )
    from rclpy.duration import Duration
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

    mode = ros.publisher(Bool, "/robot_mode", 1000)
    # Latched like a map server: a volatile publisher would never reach the
    # collector's transient-local subscription and the bad grids would go untested.
    latched = QoSProfile(
        depth=10,
        reliability=ReliabilityPolicy.RELIABLE,
        durability=DurabilityPolicy.TRANSIENT_LOCAL,
    )
    grid = ros.publisher(OccupancyGrid, "/map", latched)
    camera = ros.publisher(RosImage, "/image")
    fix = ros.publisher(NavSatFix, "/gps_fix")
    for pub in (mode, grid, camera, fix):
        ros.wait_subscribed(pub)
    grid.publish(OccupancyGrid())  # empty
    broken = OccupancyGrid()
    broken.info.width = broken.info.height = 100
    broken.info.resolution = 0.05
    broken.data = [0] * 10  # far fewer cells than 100 × 100
    grid.publish(broken)
    nan = NavSatFix(latitude=float("nan"), longitude=float("nan"))
    fix.publish(nan)
    huge = RosImage(height=2160, width=3840, encoding="bgr8", step=3840 * 3)
    pixels = np.zeros((2160, 3840, 3), np.uint8)
    pixels[..., 2] = 200  # red in BGR order
    huge.data = pixels.tobytes()
    camera.publish(huge)
    # On a loaded machine the 25 MB frame takes a while over DDS; the mode flood
    # must not overtake it.
    assert camera.wait_for_all_acked(Duration(seconds=30))
    time.sleep(0.5)
    for _ in range(3000):  # a flood of the same mode
        mode.publish(Bool(data=True))
    # The services still answer while the flood is being worked off.
    assert ros.trigger("/get_ftt_logging").success
    mode.publish(Bool(data=False))
    wait_for(
        lambda: Segment.objects.filter(leg=robot_leg, parent__isnull=True).count() == 2,
        20,
        what="the ITO master after the flood",
    )
    masters = list(Segment.objects.filter(leg=robot_leg, parent__isnull=True).order_by("start"))
    assert [m.segment_type_id for m in masters] == ["auto", "ito"]
    assert collector.alive(), collector.output()
    assert not MapImage.objects.exists() and not Pose.objects.exists()
    # The 4K frame was buffered before the first switch, so it belongs to the AUTO master.
    image = wait_for(
        lambda: Image.objects.filter(segment=masters[0]).first(), 20, what="the 4K frame"
    )
    from PIL import Image as PilImage

    with PilImage.open(image.image.path) as stored:
        assert stored.size == (1920, 1080)
        r, g, b = stored.convert("RGB").getpixel((10, 10))
        assert r > 150 and b < 60


def test_database_outage_loses_nothing(ros, procs, private_postgres, tmp_path):
    url = private_postgres.url
    env = {"FTT_DATABASE_URL": url}
    collector = procs.start(
        "ftt_collect",
        "--vehicle",
        "outage-bot",
        "--start-logging",
        "--name",
        "outage",
        "--spool",
        str(tmp_path / "outage.sqlite3"),
        "--params-file",
        str(_params(tmp_path)),
        name="outage",
        env=env,
    )
    drive = Drive(ros, rate=OUTAGE_RATE)
    drive.start()
    wait_for(
        lambda: private_postgres.count("telemetry_pose") > 10, 30, 0.5, "poses before the outage"
    )
    private_postgres.stop()
    down_at = time.time()
    # The outage lasts until the collector has said so and spooled each part of
    # it: fixes of the AUTO master, the take-over, fixes of the ITO master and the
    # take-over's black-box snapshot, all while the database is away.
    wait_for(lambda: "database unreachable" in collector.output(), 30, 0.2, "the outage to be seen")
    wait_for(lambda: _sent_since(drive, down_at) >= 50, 30, 0.1, "AUTO fixes in the outage")
    drive.mode = False  # a take-over while the database is away
    wait_for(
        lambda: re.search(r"snapshot \S+\.mcap: \d+ messages", collector.output()),
        60,
        0.2,
        "the take-over's snapshot written while the database is away",
    )
    wait_for(lambda: _sent_since(drive, down_at) > 120, 30, 0.1, "ITO fixes in the outage")
    private_postgres.start()
    up_at = time.time()
    # Live fixes after the return are stored too, not only the backlog.
    wait_for(lambda: "database back after" in collector.output(), 30, 0.2, "the return to be seen")
    wait_for(
        lambda: (
            private_postgres.count("telemetry_pose", f"robot_stamp > to_timestamp({up_at})") >= 10
        ),
        30,
        0.2,
        "fixes sent after the return",
    )
    drive.stop()
    stopped_at = time.time()
    wait_for(
        lambda: private_postgres.count("telemetry_pose") >= _expected(drive, stopped_at),
        60,
        1.0,
        "the spool to be replayed",
    )
    # Everything the collector received is written: a heartbeat after the drive
    # stopped says nothing is pending.
    wait_for(
        lambda: private_postgres.count(
            "rosbridge_app_collector",
            f"name = 'outage' AND pending = 0 AND last_seen > to_timestamp({stopped_at + 1})",
        ),
        30,
        0.3,
        "a heartbeat with nothing pending",
    )
    rows = private_postgres.query(
        "SELECT ST_Y(point), robot_stamp, segment_id FROM telemetry_pose ORDER BY robot_stamp"
    )
    stored = [(round(lat, 7), segment) for lat, _, segment in rows]
    assert len(stored) == len(set(stored)), "a pose was stored twice"
    # Only the fix at the take-over is in both segments (it ends one and starts the other).
    assert len(stored) - len({lat for lat, _ in stored}) == 1
    stored = [lat for lat, _ in stored]
    # Fixes that beat the first mode message to the collector have no segment
    # yet; the outage is what is under test, so count from the first stored fix.
    sent = {round(lat, 7) for t, lat in drive.sent if t > down_at - 5 and lat >= min(stored)}
    assert sent - set(stored) == set(), "a pose published around the outage is missing"
    during = [t for _, t, _ in rows if down_at < t.timestamp() < up_at]
    assert len(during) > 100
    masters = private_postgres.query(
        "SELECT segment_type_id, start FROM events_segment WHERE parent_id IS NULL ORDER BY start"
    )
    assert [m[0] for m in masters] == ["auto", "ito"]
    assert down_at < masters[1][1].timestamp() < up_at  # at the time of the switch
    children = private_postgres.query(
        "SELECT count(*) FROM events_segment WHERE parent_id IS NOT NULL"
    )
    assert children == [(1,)]
    # The take-over's black-box snapshot was spooled too and arrived after the outage.
    snapshots = wait_for(
        lambda: private_postgres.query(
            'SELECT s.segment_type_id, r.start, r."end", r.topics FROM telemetry_recording r '
            "JOIN events_segment s ON s.id = r.segment_id"
        ),
        20,
        0.5,
        "the snapshot of the take-over",
    )
    ((kind, start, end, topics),) = snapshots
    assert kind == "ito" and start < masters[1][1] < end < datetime.fromtimestamp(up_at, UTC)
    assert topics["/gps_fix"]["count"] > 50


def _sent_since(drive, t):
    return sum(1 for sent_at, _ in list(drive.sent) if sent_at > t)


def _expected(drive, stopped_at):
    # Fixes sent in the last ~0.3 s before stopping may still be in flight.
    return sum(1 for t, _ in drive.sent if t < stopped_at - 0.5) - 60


def _params(tmp_path):
    from tests.support.ros import copy_default_params

    # A short window after the take-over: its snapshot is then written (and
    # spooled) soon, well within the outage.
    path = copy_default_params(tmp_path, **EVERY_FIX, **{"snapshot.after": 2.0})
    return path


class PrivatePostgres:
    """A throwaway PostgreSQL cluster under tmp_path, on its own port: the shared
    server on 5432 is used by other engineers and must never be stopped."""

    def __init__(self, root, port: int, env: dict):
        import shutil
        from pathlib import Path

        self.bin = Path(subprocess.check_output(["pg_config", "--bindir"], text=True).strip())
        self.root, self.port, self.env = root, port, env
        self.data = root / "pgdata"
        root.mkdir(parents=True, exist_ok=True)
        shutil.chown(root, "postgres") if _is_root() else None
        self._as_postgres(
            self.bin / "initdb", "-D", self.data, "-U", "ftt", "--auth=trust", "-E", "UTF8"
        )
        self.start()
        self.url = f"postgis://ftt:ftt@127.0.0.1:{port}/ftt"
        self.psql("postgres", "CREATE DATABASE ftt")

    def load_migrated_template(self):
        """Fills database ftt with the suite's migrated template (a dump of it: 3 s
        instead of the whole chain of migrations); migrates when there is none."""
        from django.conf import settings

        from tests.support.databases import migrated_postgres_template

        name = migrated_postgres_template()
        if not name:
            self.psql("ftt", "CREATE EXTENSION postgis")
            subprocess.run(
                [sys.executable, str(ROOT / "manage.py"), "migrate", "-v0"],
                cwd=ROOT,
                check=True,
                env={**self.env, "FTT_DATABASE_URL": self.url},
                timeout=300,
            )
            return
        db = settings.DATABASES["default"]
        dump = subprocess.run(
            [
                str(self.bin / "pg_dump"),
                "-Fc",
                "-h",
                db["HOST"] or "127.0.0.1",
                "-p",
                str(db["PORT"] or 5432),
                "-U",
                db["USER"],
                "-d",
                name,
            ],
            check=True,
            capture_output=True,
            env={**os.environ, "PGPASSWORD": db["PASSWORD"]},
            timeout=120,
        ).stdout
        subprocess.run(
            [
                str(self.bin / "pg_restore"),
                "--no-owner",
                "--exit-on-error",
                *self._client("ftt"),
            ],
            input=dump,
            check=True,
            capture_output=True,
            timeout=120,
        )

    def _client(self, db):
        """A PostgreSQL client's arguments for database ``db`` of this cluster."""
        return ["-h", "127.0.0.1", "-p", str(self.port), "-U", "ftt", "-d", db]

    def _as_postgres(self, *args):
        cmd = [str(a) for a in args]
        if _is_root():
            cmd = ["runuser", "-u", "postgres", "--", *cmd]
        subprocess.run(cmd, check=True, capture_output=True, timeout=120)

    def start(self):
        self._as_postgres(
            self.bin / "pg_ctl",
            "-D",
            self.data,
            "-l",
            self.root / "server.log",
            "-w",
            "-o",
            f"-p {self.port} -k {self.root} -c listen_addresses=127.0.0.1 -c fsync=off",
            "start",
        )

    def stop(self):
        self._as_postgres(self.bin / "pg_ctl", "-D", self.data, "-m", "fast", "-w", "stop")

    def psql(self, db, sql):
        subprocess.run(
            [
                "psql",
                *self._client(db),
                "-v",
                "ON_ERROR_STOP=1",
                "-c",
                sql,
            ],
            check=True,
            capture_output=True,
        )

    def query(self, sql):
        import psycopg2

        with psycopg2.connect(host="127.0.0.1", port=self.port, user="ftt", dbname="ftt") as c:
            with c.cursor() as cur:
                cur.execute(sql)
                return cur.fetchall()

    def count(self, table, where="true"):
        try:
            return self.query(f"SELECT count(*) FROM {table} WHERE {where}")[0][0]
        except Exception:
            return 0


def _is_root():
    import os

    return os.geteuid() == 0


@pytest.fixture
def private_postgres(tmp_path, ros_env, procs):
    import os
    import shutil

    if not shutil.which("pg_config"):
        pytest.skip("no PostgreSQL server binaries for a private cluster")
    import tempfile
    from pathlib import Path

    # Not under tmp_path: pytest's directory is private to root, and the server
    # must run as the postgres user when the tests run as root.
    root = Path(tempfile.mkdtemp(prefix="ftt-ros-pg-"))
    root.chmod(0o755)
    pg = PrivatePostgres(root, 55400 + os.getpid() % 500, ros_env)
    env = {"FTT_DATABASE_URL": pg.url}
    pg.load_migrated_template()
    for args in (
        [
            "shell",
            "-c",
            "from events.models import Vehicle; from events.services "
            "import logs; v = Vehicle.objects.create(key='outage-bot', "
            "short_description='x'); logs.create_leg(shift=logs.create_shift("
            "test_event=logs.create_test_event(), vehicle=v))",
        ],
    ):
        p = procs.start(*args, name=f"setup-{args[0]}", env=env)
        assert p.popen.wait(180) == 0, p.output()
    yield pg
    procs.stop_all()
    try:
        pg.stop()
    except subprocess.CalledProcessError:
        pass
    shutil.rmtree(root, ignore_errors=True)
