"""A simulated robot with its collector, run in its own process by the e2e tests.

It registers like `manage.py ftt_collect` does, answers start/stop logging,
and writes segments and poses through the service layer when the test tells
it to on stdin.  After each write has committed it prints "DONE <unix time>".
"""

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
