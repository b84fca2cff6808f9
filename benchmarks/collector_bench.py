"""Shared by the collector benchmarks: a ROS domain of their own, Django set up,
a throw-away vehicle and leg, the collector and the benchmark robot as processes.

Import it before anything of Django or ROS: it sets the environment they read.
"""

import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
os.environ.setdefault("DJANGO_SETTINGS_MODULE", "ftt_site.settings")
os.environ["ROS_DOMAIN_ID"] = os.environ.get("FTT_ROS_DOMAIN_ID") or str(40 + os.getpid() % 20)
os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
os.environ.pop("RMW_IMPLEMENTATION", None)

import django  # noqa: E402

django.setup()

from events.models import Vehicle  # noqa: E402
from events.services import deletion, logs  # noqa: E402
from rosbridge_app.collector import params as P  # noqa: E402
from rosbridge_app.models import Collector  # noqa: E402

MANAGE = [sys.executable, str(ROOT / "manage.py")]
# The benchmark robot: GPS 100 Hz, TF 50 Hz, a 640×480 rgb8 camera at 10 Hz and
# a 2000×2000 occupancy grid that changes every second; no mode switches.
ROBOT = [
    "--gps-rate",
    "100",
    "--tf-rate",
    "50",
    "--camera-rate",
    "10",
    "--camera-size",
    "640x480",
    "--map-size",
    "2000",
    "--map-rate",
    "1",
    "--mode-rate",
    "0",
]


def load() -> str:
    """The machine is shared: every figure is printed with the load average."""
    return "load {:.2f} {:.2f} {:.2f}".format(*os.getloadavg())


class Bench:
    """A throw-away vehicle with an open leg, a work folder, and the processes."""

    def __init__(self, label: str, **parameters):
        self.key = f"{label}-{os.getpid()}"
        self.vehicle = Vehicle.objects.create(key=self.key, short_description=f"{label} benchmark")
        self.event = logs.create_test_event(location=f"{label} benchmark")
        self.leg = logs.create_leg(
            shift=logs.create_shift(test_event=self.event, vehicle=self.vehicle)
        )
        self.work = Path(tempfile.mkdtemp(prefix=f"ftt-{label}-"))
        self.params = self.work / "params.yaml"
        values = P.read_file(P.DEFAULT_FILE)
        values.update({"vehicle": self.key, **parameters})
        P.write_file(self.params, values)
        self.env = {
            **os.environ,
            "PYTHONUNBUFFERED": "1",
            "FTT_DATA_DIR": str(self.work),
            "FTT_MEDIA_ROOT": str(self.work / "media"),
        }

    def collector(
        self, spool: Path, log: Path, env: dict | None = None, manage=MANAGE
    ) -> subprocess.Popen:
        """``manage``: another checkout's manage.py runs the collector for an A/B run."""
        return subprocess.Popen(
            [
                *manage,
                "ftt_collect",
                "--params-file",
                str(self.params),
                "--name",
                self.key,
                "--spool",
                str(spool),
                "--start-logging",
            ],
            env={**self.env, **(env or {})},
            stdout=open(log, "wb"),  # noqa: SIM115 - closed with the process
            stderr=subprocess.STDOUT,
        )

    def robot(self, seconds: float, **popen) -> subprocess.Popen:
        return subprocess.Popen(
            [
                *MANAGE,
                "ftt_simulate",
                *ROBOT,
                "--duration",
                str(seconds),
                "--wait-for-subscriber",
                "30",
            ],
            env=self.env,
            **popen,
        )

    def close(self) -> None:
        deletion.delete(self.event)
        Collector.objects.filter(name=self.key).delete()
        deletion.delete(self.vehicle)
        shutil.rmtree(self.work, ignore_errors=True)
