"""A simulated robot that publishes what its script says, in its own process.

    python -m tests.support.scripted_robot SCRIPT.json

The script: {"topics": {topic: "pkg/msg/Type"}, "rate": Hz,
"phases": [[seconds, {topic: {field: value}}], ...]}. Each phase sets the
values of some topics; every topic is published at ``rate`` with its current
values (a topic without values is silent), and a NavSatFix on /gps_fix
moving north. It starts once every topic has a subscriber. Run in its own
process so that interface packages built for the test (PYTHONPATH,
LD_LIBRARY_PATH) load as on a robot.
"""

import importlib
import json
import sys
import time


def _class(typename: str):
    pkg, kind, name = typename.split("/")
    return getattr(importlib.import_module(f"{pkg}.{kind}"), name)


def main(path: str) -> None:
    import rclpy
    from sensor_msgs.msg import NavSatFix

    script = json.loads(open(path).read())
    rclpy.init()
    node = rclpy.create_node("scripted_robot")
    publishers = {t: node.create_publisher(_class(k), t, 10) for t, k in script["topics"].items()}
    fix_publisher = node.create_publisher(NavSatFix, "/gps_fix", 10)
    deadline = time.monotonic() + 30
    while any(p.get_subscription_count() == 0 for p in publishers.values()):
        if time.monotonic() > deadline:
            sys.exit("no subscriber on " + ", ".join(publishers))
        time.sleep(0.05)
    values: dict = {}
    period = 1.0 / script["rate"]
    start = end = time.monotonic()
    for seconds, changes in script["phases"]:
        values.update(changes)
        end += seconds
        while time.monotonic() < end:
            for topic, fields in values.items():
                if fields is not None:
                    publishers[topic].publish(_class(script["topics"][topic])(**fields))
            fix = NavSatFix(latitude=50.0 + (time.monotonic() - start) * 1e-5, longitude=8.0)
            fix.status.service = 1
            fix_publisher.publish(fix)
            time.sleep(period)
    print("done", flush=True)
    node.destroy_node()
    rclpy.shutdown()


if __name__ == "__main__":
    main(sys.argv[1])
