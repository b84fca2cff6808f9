"""The browser tests' server and simulated robot.

:class:`Server` runs daphne in a process of its own; ``ROBOT`` is a simulated
robot with its collector, run in its own process by the e2e tests.

It registers like `manage.py ftt_collect` does, answers start/stop logging,
and writes segments and poses through the service layer when the test tells
it to on stdin.  After each write has committed it prints "DONE <unix time>".
"""

import os
import socket
import subprocess
import sys
import textwrap
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
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


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Server:
    """A daphne process plus a way to run Django code in other processes."""

    def __init__(self, data_dir: Path, tile_url: str):
        self.port = _free_port()
        self.url = f"http://127.0.0.1:{self.port}"
        self.env = {
            k: v for k, v in os.environ.items() if not k.startswith(("FTT_", "DJANGO_ALLOW"))
        }
        self.env.update(
            FTT_DATA_DIR=str(data_dir),
            FTT_TILE_URL=tile_url,
            FTT_ALLOWED_HOSTS="127.0.0.1,localhost",
            DJANGO_SETTINGS_MODULE="ftt_site.settings",
            PYTHONPATH=str(ROOT),
        )
        self.process = None

    def manage(self, *args, timeout=120) -> str:
        result = subprocess.run(
            [sys.executable, "manage.py", *args],
            cwd=ROOT,
            env=self.env,
            capture_output=True,
            text=True,
            timeout=timeout,
        )
        assert result.returncode == 0, result.stderr[-3000:]
        return result.stdout

    def python(self, code: str) -> str:
        """Run Django code in a separate process (the robot, an admin script)."""
        return self.manage("shell", "-c", textwrap.dedent(code))

    def spawn(self, code: str) -> subprocess.Popen:
        return subprocess.Popen(
            [sys.executable, "manage.py", "shell", "-c", textwrap.dedent(code)],
            cwd=ROOT,
            env=self.env,
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            bufsize=1,
        )

    def start(self):
        self.manage("migrate", "--noinput", timeout=300)
        ARTIFACTS.mkdir(parents=True, exist_ok=True)
        self.log = open(ARTIFACTS / "daphne.log", "w")  # noqa: SIM115 - open while it runs
        self.process = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "daphne",
                "-b",
                "127.0.0.1",
                "-p",
                str(self.port),
                "ftt_site.asgi:application",
            ],
            cwd=ROOT,
            env=self.env,
            # Kept as an artifact: when a page hangs, the server's side tells why.
            stdout=self.log,
            stderr=subprocess.STDOUT,
        )
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline:
            try:
                with socket.create_connection(("127.0.0.1", self.port), timeout=0.5):
                    return
            except OSError:
                time.sleep(0.2)
        raise RuntimeError("daphne did not start")

    def stop(self):
        if self.process is not None:
            self.process.terminate()
            try:
                self.process.wait(10)
            except subprocess.TimeoutExpired:
                self.process.kill()
            self.log.close()


# The three screens the GUI is used on: a laptop, a tablet held in one hand, a phone.
VIEWPORTS = {
    "laptop": {"viewport": {"width": 1366, "height": 768}},
    "tablet": {"viewport": {"width": 1024, "height": 768}, "has_touch": True, "is_mobile": True},
    "phone": {"viewport": {"width": 390, "height": 844}, "has_touch": True, "is_mobile": True},
}

# Whatever sticks out of the window or scrolls sideways inside its box; the maps'
# panes are clipped by Leaflet on purpose, and a long value scrolls in its input.
OVERFLOWING = """() => {
  const width = document.documentElement.clientWidth;
  const out = [];
  for (const el of document.querySelectorAll("body *")) {
    if (el.closest(".leaflet-container, dialog:not([open])")) continue;
    if (["INPUT", "SELECT", "TEXTAREA", "OPTION"].includes(el.tagName)) continue;
    const r = el.getBoundingClientRect();
    if (!r.width || !r.height) continue;
    const style = getComputedStyle(el);
    const clips = style.overflowX !== "visible";
    if (r.right > width + 0.5 || r.left < -0.5 || (clips && el.scrollWidth > el.clientWidth + 1)) {
      out.push(`${el.tagName.toLowerCase()}#${el.id}.${el.className}`);
    }
  }
  if (document.documentElement.scrollWidth > width) out.push("page");
  return out;
}"""

# Main actions smaller than a 44 px touch target (selector as argument).
SMALL = """(selector) => Array.from(document.querySelectorAll(selector))
  .filter((el) => el.getClientRects().length && !el.closest("[hidden]"))
  .map((el) => [el.id || el.textContent.trim().slice(0, 20), el.getBoundingClientRect()])
  .filter(([, r]) => r.height < 44 || r.width < 44)
  .map(([name, r]) => `${name}: ${Math.round(r.width)}x${Math.round(r.height)}`)"""


# axe-core (npm) and the check of a page for serious or critical accessibility problems.
AXE = ROOT / "node_modules" / "axe-core" / "axe.min.js"

SERIOUS = """async () => {
  const result = await axe.run(document, { resultTypes: ["violations"] });
  return result.violations
    .filter((v) => ["serious", "critical"].includes(v.impact))
    .map((v) => `${v.id}: ${v.nodes.map((n) => n.target.join(" ")).join(", ")}`);
}"""


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
from telemetry.services import recording

KEY = "{key}"
vehicle = Vehicle.objects.get(key=KEY)
state = {{"logging": False, "leg": None}}
parameters = {{"topics.gps_fix": "gps_fix", "params.use_tf": True, "params.pose_min_distance": 0.5}}
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
        if word in ("auto", "ito"):
            segments.report_mode(
                leg, word, gps=GpsPosition(lon, lat), local=LocalPosition(x, y, "map")
            )
        elif word == "poses":
            fixes, local = [], []
            for _ in range(5):
                lon += 0.0001
                lat += 0.00005
                x += 7.07
                y += 5.56
                fixes.append(recording.GpsFix(lon, lat))
                local.append(recording.MapPose(x, y, "map"))
            recording.record_poses(open_master(leg), fixes)
            recording.record_local_poses(open_master(leg), local)
        elif word == "map":
            recording.record_map(
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
