"""A simulated robot that publishes what its script says, in its own process.

    python -m tests.support.scripted_robot SCRIPT.json

The script: {"topics": {topic: "pkg/msg/Type"}, "rate": Hz,
"phases": [[seconds, {topic: {field: value}}], ...]}, optionally
"best_effort": [topic, ...] (published BEST_EFFORT, as sensor drivers do),
"on_change": [topic, ...] (published only when a phase changes its values) and
"wait": false (start at once, not once every topic has a subscriber). Each
phase sets the values of some topics; every topic is published at ``rate``
with its current values (a topic without values is silent), and a NavSatFix on
/gps_fix moving north; fields named "header" get the time of publishing.
Run in its own process so that interface packages built for the test
(PYTHONPATH, LD_LIBRARY_PATH) load as on a robot.
"""

import importlib
import json
import sys
import time


def _class(typename: str):
    pkg, kind, name = typename.split("/")
    return getattr(importlib.import_module(f"{pkg}.{kind}"), name)


def _message(typename: str, fields: dict):
    cls = _class(typename)
    fields = dict(fields)
    stamped = "header" in fields
    fields.pop("header", None)
    nested = {k: v for k, v in fields.items() if isinstance(v, dict)}
    msg = cls(**{k: v for k, v in fields.items() if k not in nested})
    for name, values in nested.items():
        for key, value in values.items():
            setattr(getattr(msg, name), key, value)
    if stamped:
        t = time.time()
        msg.header.stamp.sec, msg.header.stamp.nanosec = int(t), int(t % 1 * 1e9)
    return msg


def main(path: str) -> None:
    import rclpy
    from rclpy.qos import qos_profile_sensor_data
    from sensor_msgs.msg import NavSatFix

    script = json.loads(open(path).read())
    rclpy.init()
    node = rclpy.create_node("scripted_robot")
    best_effort = set(script.get("best_effort", ()))
    publishers = {
        t: node.create_publisher(_class(k), t, qos_profile_sensor_data if t in best_effort else 10)
        for t, k in script["topics"].items()
    }
    fix_publisher = node.create_publisher(NavSatFix, "/gps_fix", 10)
    deadline = time.monotonic() + 30
    while script.get("wait", True) and any(
        p.get_subscription_count() == 0 for p in publishers.values()
    ):
        if time.monotonic() > deadline:
            sys.exit("no subscriber on " + ", ".join(publishers))
        time.sleep(0.05)
    values: dict = {}
    on_change = set(script.get("on_change", ()))
    period = 1.0 / script["rate"]
    start = end = time.monotonic()
    for seconds, changes in script["phases"]:
        values.update(changes)
        due = set(changes)
        end += seconds
        while time.monotonic() < end:
            for topic, fields in values.items():
                if fields is not None and (topic not in on_change or topic in due):
                    publishers[topic].publish(_message(script["topics"][topic], fields))
            due.clear()
            fix = NavSatFix(latitude=50.0 + (time.monotonic() - start) * 1e-5, longitude=8.0)
            fix.status.service = 1
            fix_publisher.publish(fix)
            time.sleep(period)
    print("done", flush=True)
    node.destroy_node()
    rclpy.shutdown()


if __name__ == "__main__":
    main(sys.argv[1])
