"""What the collector subscribes to: the inputs, their message types and QoS.

:func:`wanted_inputs` is the one table of the collector's inputs (the mode,
positions, maps, camera); the node subscribes to each through
:func:`drained_subscription`.
"""

import functools
import logging

from django.utils.translation import gettext
from geometry_msgs.msg import PoseStamped
from nav_msgs.msg import OccupancyGrid
from rclpy.qos import (
    DurabilityPolicy,
    HistoryPolicy,
    QoSProfile,
    ReliabilityPolicy,
)
from sensor_msgs.msg import CompressedImage, Image, NavSatFix
from tf2_msgs.msg import TFMessage

from rosbridge_app.collector.message_fields import message_class
from rosbridge_app.collector.modes import message_type

log = logging.getLogger("ftt.collector")
# Positions may come at 1 kHz: the subscription's history holds 2 s of them, so
# a moment in which this process's other threads hold the interpreter loses nothing.
POSITION_DEPTH = 2000
# The most messages one callback takes from its subscription besides its own.
DRAIN = 200
# While draining sensor data, the mode subscription is looked at this often.
AHEAD_EVERY = 20
# The mode is never dropped: a reliable history deep enough for a burst of switches.
MODE_DEPTH = 50

RELIABLE_LATCHED = QoSProfile(
    history=HistoryPolicy.KEEP_LAST,
    depth=1,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.TRANSIENT_LOCAL,
)


def qos(depth: int, reliable: bool, latched: bool = False) -> QoSProfile:
    return QoSProfile(
        history=HistoryPolicy.KEEP_LAST,
        depth=depth,
        reliability=ReliabilityPolicy.RELIABLE if reliable else ReliabilityPolicy.BEST_EFFORT,
        durability=DurabilityPolicy.TRANSIENT_LOCAL if latched else DurabilityPolicy.VOLATILE,
    )


def wanted_inputs(get, pipe) -> list[tuple]:
    """(name, message type, topic, QoS, handler(msg, at)) of every input the
    parameters ask for (``get(name)``: a parameter's value), handled by the
    pipeline ``pipe``."""
    reliable = get("params.sensor_reliable")
    wanted = (
        mode_inputs(get, pipe)
        + reason_inputs(pipe)
        + [
            (
                "gps_fix",
                NavSatFix,
                get("topics.gps_fix"),
                qos(POSITION_DEPTH, reliable),
                pipe.on_fix,
            ),
            ("map", OccupancyGrid, get("topics.map"), RELIABLE_LATCHED, pipe.on_grid),
            (
                "map_jpeg",
                CompressedImage,
                get("topics.map_jpeg"),
                RELIABLE_LATCHED,
                pipe.on_map_jpeg,
            ),
            ("image", Image, get("topics.image"), qos(2, reliable), pipe.on_image),
            (
                "image_compressed",
                CompressedImage,
                get("topics.image_compressed"),
                qos(2, reliable),
                lambda m, at: pipe.on_image(m, at, compressed=True),
            ),
        ]
    )
    if get("params.use_tf"):
        wanted += [
            ("tf", TFMessage, get("topics.tf"), qos(POSITION_DEPTH, True), pipe.on_tf),
            (
                "tf_static",
                TFMessage,
                get("topics.tf_static"),
                qos(100, True, latched=True),
                lambda m, at: pipe.on_tf(m, at, static=True),
            ),
        ]
    else:
        wanted.append(
            (
                "local_pose",
                PoseStamped,
                get("topics.local_pose"),
                qos(POSITION_DEPTH, reliable),
                pipe.on_pose,
            )
        )
    return wanted


MODE_INPUT = "robot_mode"
MODE_SOURCE_INPUT = "mode_source_"


def is_mode_input(name: str) -> bool:
    """Whether an input carries the mode: subscribed reliable and latched too,
    with the send time of each message, and taken ahead of sensor data."""
    return name == MODE_INPUT or name.startswith(MODE_SOURCE_INPUT)


def mode_inputs(get, pipe) -> list[tuple]:
    """The mode topic, or one input per mode source (params.mode_sources)."""
    combiner = pipe.mode_sources
    if combiner is None:
        return [
            (
                MODE_INPUT,
                message_type(get("params.robot_mode_type")),
                get("topics.robot_mode"),
                qos(MODE_DEPTH, True),
                pipe.on_mode,
            )
        ]
    wanted = []
    for indices in combiner.config.by_topic().values():
        source = combiner.config.sources[indices[0]]
        try:
            cls = message_class(source.type)
        except (ImportError, AttributeError):
            # The parameter check refuses such types; this is one removed since.
            log.error(
                gettext("mode source %s: message type %s is not installed"),
                source.topic,
                source.type,
            )
            continue
        handler = functools.partial(pipe.on_mode_source, indices)
        wanted.append(
            (
                f"{MODE_SOURCE_INPUT}{indices[0]}",
                cls,
                source.topic,
                qos(MODE_DEPTH, True),
                handler,
            )
        )
    return wanted


def reason_inputs(pipe) -> list[tuple]:
    """One input per topic of params.reason_rules that is not a mode source
    (a mode source hands its messages to the rules itself)."""
    if pipe.reasons is None:
        return []
    taken = set()
    if pipe.mode_sources is not None:
        taken = {s.topic.lstrip("/") for s in pipe.mode_sources.config.sources}
    wanted = []
    for i, (topic, typename) in enumerate(pipe.reasons.topics().items()):
        if topic.lstrip("/") in taken:
            continue
        try:
            cls = message_class(typename)
        except (ImportError, AttributeError):
            log.error(gettext("reason rule %s: message type %s is not installed"), topic, typename)
            continue
        handler = functools.partial(pipe.on_reason_signal, topic)
        wanted.append((f"reason_{i}", cls, topic, qos(MODE_DEPTH, True), handler))
    return wanted


def volatile_map_inputs(pipe) -> list[tuple]:
    """(name, message type, handler) of the maps' second, volatile subscriptions:
    only a TRANSIENT_LOCAL subscription gets a map latched before it existed,
    but it never matches a volatile publisher (cartographer's /map).  A map
    that arrives twice is dropped by the pipeline's checksum or byte comparison."""
    from nav_msgs.msg import OccupancyGrid
    from sensor_msgs.msg import CompressedImage

    return [("map", OccupancyGrid, pipe.on_grid), ("map_jpeg", CompressedImage, pipe.on_map_jpeg)]


def drained_subscription(
    node, msg_type, topic, callback, qos_profile, raw=False, with_info=False, ahead=None, **options
):
    """A subscription of ``node`` whose callback also takes the messages waiting
    behind its own (at most DRAIN): the executor builds a new wait set for every
    message it takes, which in Python costs more than converting a fix.
    ``with_info``: the callback also gets rmw's message info (its source
    timestamp); ``ahead()`` is called every AHEAD_EVERY messages, so that the
    mode is taken before a long backlog of sensor data.  ``options`` go to
    ``create_subscription`` (event callbacks)."""
    subscription = None

    def take() -> bool:
        with subscription.handle:
            taken = subscription.handle.take_message(msg_type, raw)
        if taken is None:
            return False
        callback(*taken) if with_info else callback(taken[0])
        return True

    def receive(*msg_and_info):
        callback(*msg_and_info)
        for n in range(1, DRAIN + 1):
            if ahead is not None and n % AHEAD_EVERY == 0:
                ahead()
            if not take():
                return

    def receive_message(msg):
        receive(msg)

    def receive_with_info(msg, info):
        receive(msg, info)

    subscription = node.create_subscription(
        msg_type,
        topic,
        receive_with_info if with_info else receive_message,
        qos_profile,
        raw=raw,
        **options,
    )

    def take_waiting() -> None:
        for _ in range(DRAIN):
            if not take():
                return

    subscription.take_waiting = take_waiting
    return subscription
