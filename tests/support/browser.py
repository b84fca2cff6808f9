"""The browser tests' server and simulated robot.

:class:`Server` runs the production server in a process of its own; ``ROBOT``
is a simulated robot with its collector, run in its own process by the e2e tests.

It registers like `manage.py ftt_collect` does, answers start/stop logging,
and writes segments and poses through the service layer when the test tells
it to on stdin.  After each write has committed it prints "DONE <unix time>".
"""

import contextlib
import os
import re
import subprocess
import sys
import textwrap
from pathlib import Path
from urllib.parse import unquote, urlsplit, urlunsplit

import psycopg

from tests.support.web import ROOT, WebServer, end

# Not under test-results/: pytest-playwright empties that folder when a session starts.
ARTIFACTS = Path(os.environ.get("FTT_E2E_ARTIFACTS", ROOT / "test-artifacts" / "e2e"))
PASSWORD = "field-test-2026"


def system_chromium() -> str | None:
    """The distribution's Chromium if it starts (the same test scripts/setup.sh
    makes); None means Playwright's own build, which the setup then fetched."""
    found = subprocess.run(
        ["bash", "-c", f"source {ROOT}/scripts/lib.sh && ftt_working_chromium"],
        capture_output=True,
        text=True,
    )
    if found.returncode != 0:
        return None
    return found.stdout.strip()


class Server(WebServer):
    """The production server (as scripts/run.sh starts it, one worker) and the job
    worker beside it, plus a way to run Django code in other processes."""

    def __init__(
        self,
        data_dir: Path,
        tile_url: str,
        database_url: str = "",
        name: str = "server",
        root: Path = ROOT,
    ):
        """SpatiaLite in ``data_dir`` unless ``database_url`` names a PostgreSQL
        database; ``name``: its log's, under ARTIFACTS; ``root``: the checkout whose
        code runs (a benchmark compares two)."""
        env = {"FTT_DATA_DIR": str(data_dir), "FTT_TILE_URL": tile_url}
        if database_url:
            env["FTT_DATABASE_URL"] = database_url
        super().__init__(env, log=ARTIFACTS / f"{name}.log", root=root)
        self.name = name
        self.worker = None

    def spawn(self, code: str) -> subprocess.Popen:
        return subprocess.Popen(
            [sys.executable, "manage.py", "shell", "-c", textwrap.dedent(code)],
            cwd=self.root,
            env=self.env,
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            bufsize=1,
        )

    def start(self):
        ARTIFACTS.mkdir(parents=True, exist_ok=True)
        super().start()
        self.worker = subprocess.Popen(
            [sys.executable, "manage.py", "ftt_worker", "--interval", "0.5"],
            cwd=self.root,
            env=self.env,
            stdout=self.log,
            stderr=subprocess.STDOUT,
        )
        return self

    def stop(self):
        end(self.worker, 10)
        super().stop()


def open_leg_code(key: str) -> str:
    """Django code for :meth:`Server.python`: vehicle ``key`` (``v``) with an open
    test event "Gelände ``key``" (``e``), shift (``s``) and leg."""
    return f"""
from events.models import Performer, PoseSource, Vehicle
from events.services import logs
Performer.objects.get_or_create(institution="Fraunhofer FKIE")
PoseSource.objects.get_or_create(key="gps", defaults={{"short_description": "GPS"}})
v = Vehicle.objects.create(key="{key}", short_description="Rover {key}")
e = logs.create_test_event(location="Gelände {key}", time_zone="Europe/Berlin")
s = logs.create_shift(test_event=e, vehicle=v)
logs.create_leg(shift=s, weather_id="sunny")
"""


def choose_event(page, key):
    """Pick the test event made by :func:`open_leg_code`; its shift and leg follow."""
    from playwright.sync_api import expect

    option = page.locator("#pick-event option", has_text=f"Gelände {key}")
    value = option.get_attribute("value")
    page.select_option("#pick-event", value=value)
    # The page may have opened another leg (one a collector logs into): wait until
    # this event's shift and leg are chosen, not only for a leg to be shown.
    expect(page).to_have_url(re.compile(rf"[?&]event={value}&shift=\d+&leg=\d+"))
    expect(page.locator("#segments-section")).to_be_visible()


def end_level(page, level):
    """End the selected test event, shift or leg ("event", "shift", "leg"): the
    cockpit asks first, naming what ends; the question is answered yes."""
    from playwright.sync_api import expect

    page.locator(f'[data-action="end"][data-level="{level}"]').click()
    confirm = page.locator("#confirm-dialog")
    expect(confirm).to_be_visible()
    confirm.locator('button[value="yes"]').click()
    expect(confirm).to_be_hidden()


USERS = f"""
from django.contrib.auth.models import Group, User
from events.models import Personnel
def user(name, role, full):
    u = User.objects.create_user(name, password={PASSWORD!r}, first_name=full)
    u.groups.add(Group.objects.get(name=role))
    return u
admin = user("ada", "administrator", "Ada Admin")
admin.is_staff = True
admin.save()
op = user("otto", "operator", "Otto Operator")
Personnel.objects.create(name="Jörg Müller", institution="FKIE", user=op)
user("vera", "viewer", "Vera Viewer")
"""


def _maintenance_connection(parts):
    return psycopg.connect(
        host=parts.hostname,
        port=parts.port or 5432,
        user=unquote(parts.username or ""),
        password=unquote(parts.password or ""),
        dbname="postgres",
        autocommit=True,
    )


def fresh_database(url: str, suffix: str, template: str = "") -> str:
    """A database next to the one ``url`` names (PostgreSQL), empty or a copy of
    ``template``; returns its URL."""
    parts = urlsplit(url)
    name = f"test_{parts.path.lstrip('/')}_{suffix}"
    copy_of = f' TEMPLATE "{template}"' if template else ""
    with _maintenance_connection(parts) as conn:
        conn.execute(f'DROP DATABASE IF EXISTS "{name}" WITH (FORCE)')
        conn.execute(f'CREATE DATABASE "{name}"{copy_of}')
    return urlunsplit(parts._replace(path=f"/{name}"))


def drop_database(url: str) -> None:
    parts = urlsplit(url)
    with _maintenance_connection(parts) as conn:
        conn.execute(f'DROP DATABASE IF EXISTS "{parts.path.lstrip("/")}" WITH (FORCE)')


def add_users(server) -> None:
    """The browser tests' accounts: ada (administrator), otto (operator), vera (viewer)."""
    server.python(USERS)


def session_code(username: str, group: str) -> str:
    """Django code for :meth:`Server.python`: a user of ``group`` (in ``user``) with a
    signed-in session (in ``s``), for a client that cannot type a password."""
    return f"""
from django.contrib.auth.models import Group, User
from django.contrib.sessions.backends.db import SessionStore
user = User.objects.create_user({username!r}, password="x")
user.groups.add(Group.objects.get(name={group!r}))
s = SessionStore()
s["_auth_user_id"] = str(user.pk)
s["_auth_user_backend"] = "django.contrib.auth.backends.ModelBackend"
s["_auth_user_hash"] = user.get_session_auth_hash()
s.create()
"""


@contextlib.contextmanager
def german_page(browser, server, username="vera"):
    """A page of a German browser, signed in as ``username`` (the login form in German)."""
    context = browser.new_context(locale="de-DE")
    try:
        page = context.new_page()
        page.goto(f"{server.url}/login/")
        page.get_by_label("Benutzername").fill(username)
        page.get_by_label("Passwort").fill(PASSWORD)
        page.get_by_role("button", name="Anmelden").click()
        page.wait_for_url(f"{server.url}/")
        yield page
    finally:
        context.close()


def login(page, server, username):
    page.goto(f"{server.url}/login/")
    page.get_by_label("User name").fill(username)
    page.get_by_label("Password").fill(PASSWORD)
    page.get_by_role("button", name="Sign in").click()
    page.wait_for_url(f"{server.url}/")


ROBOT = r"""
import sys, threading, time
from datetime import UTC, datetime

from events.models import Leg, Vehicle
from events.selectors.logs import open_leg_for_vehicle, open_master
from events.services import segments
from events.services.segments import GpsPosition, LocalPosition
from rosbridge_app.services import collectors
from telemetry.services import pose_writes
from telemetry.services import map_images

KEY = "{key}"
vehicle = Vehicle.objects.get(key=KEY)
state = {{"logging": False, "leg": None}}
parameters = {{
    "topics.gps_fix": "gps_fix", "params.use_tf": True, "params.pose_min_distance": 0.5,
    "params.mode_sources": "",
}}
graph = [
    {{"name": "/fix", "types": ["sensor_msgs/msg/NavSatFix"]}},
    {{"name": "/camera", "types": ["sensor_msgs/msg/Image"]}},
]
lock = threading.Lock()


def beat():
    now = datetime.now(UTC).isoformat()
    return collectors.heartbeat(
        "sim-" + KEY, vehicle=vehicle, logging=state["logging"], leg_id=state["leg"],
        host="e2e", state="simulated", inputs={{"robot_mode": {{"last_received": now}}}},
        parameters=dict(parameters), topics=graph,
    )


def loop():
    while True:
        with lock:
            collector = beat()
            for command in collectors.take_commands(collector):
                if command.kind == "start_logging":
                    leg = open_leg_for_vehicle(vehicle)
                    state.update(logging=True, leg=leg.pk if leg else None)
                elif command.kind == "stop_logging":
                    if state["leg"]:
                        segments.close_open_master(Leg.objects.get(pk=state["leg"]))
                    state.update(logging=False, leg=None)
                elif command.kind == "set_parameters":
                    parameters.update(command.arguments["parameters"])
                beat()
                collectors.finish_command(command, True, f"{{command.kind}} done")
        time.sleep(0.3)


threading.Thread(target=loop, daemon=True).start()
time.sleep(0.5)
print("READY", flush=True)
lon, lat = 7.1000, 50.6000
x, y = 0.0, 0.0
PNG = bytes.fromhex(
    "89504e470d0a1a0a0000000d4948445200000002000000020802000000fdd49a73"
    "0000001249444154789c633871e284868606038402002d0e05a1debd6afb"
    "0000000049454e44ae426082"
)
for line in sys.stdin:
    word = line.split()[0]
    with lock:
        leg = open_leg_for_vehicle(vehicle)
        if word.split(":")[0] in ("auto", "ito"):
            # ito:safety: a take-over whose reason the robot suggests
            mode, _, suggested = word.partition(":")
            segments.report_mode(
                leg, mode, gps=GpsPosition(lon, lat), local=LocalPosition(x, y, "map"),
                suggested_reason=suggested or None,
            )
        elif word == "poses":
            fixes, local = [], []
            for _ in range(5):
                lon += 0.0001
                lat += 0.00005
                x += 7.07
                y += 5.56
                fixes.append(pose_writes.GpsFix(lon, lat))
                local.append(pose_writes.MapPose(x, y, "map", yaw=0.666))
            pose_writes.store_poses(open_master(leg), fixes)
            pose_writes.store_local_poses(open_master(leg), local)
        elif word == "map":
            map_images.store_map(
                leg.shift, png=PNG, frame="map", width=2, height=2, resolution=40.0,
                origin_x=-10.0, origin_y=-10.0,
            )
    print("DONE", time.time(), flush=True)
"""


class Robot:
    def __init__(self, server, vehicle_key):
        self.process = server.spawn(ROBOT.format(key=vehicle_key))
        self._expect("READY")

    def _expect(self, word: str) -> str:
        # Django's shell prints its own banner lines first.
        for line in self.process.stdout:
            if line.startswith(word):
                return line
        raise AssertionError(f"robot ended before {word}: " + self.process.stderr.read()[-3000:])

    def do(self, word: str) -> float:
        """Send one step; returns the time its write was committed."""
        self.process.stdin.write(word + "\n")
        self.process.stdin.flush()
        return float(self._expect("DONE").split()[1])

    def stop(self):
        self.process.stdin.close()
        self.process.terminate()
        self.process.wait(10)
