"""manage.py ftt_simulate: a simulated robot publishing over ROS 2 (docs/collector.md)."""

import time

import rclpy
from django.core.management.base import BaseCommand
from django.utils.formats import number_format
from django.utils.translation import gettext as _
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor

from common.numbers import short
from events.models import Vehicle
from events.selectors.logs import open_leg_for_vehicle
from events.services import logs
from rosbridge_app.collector import modes
from rosbridge_app.collector.simulator import SimConfig, SimulatedRobot


class Command(BaseCommand):
    help = _("Publish a simulated drive: mode switches, GPS, TF, map and camera.")

    def add_arguments(self, parser):
        d = SimConfig()
        a = parser.add_argument
        a("--latitude", type=float, default=d.latitude, help=_("Centre of the circle (°)."))
        a("--longitude", type=float, default=d.longitude, help=_("Centre of the circle (°)."))
        a("--radius", type=float, default=d.radius, help=_("Circle radius (m)."))
        a("--speed", type=float, default=d.speed, help=_("Speed (m/s)."))
        a(
            "--switch-every",
            type=float,
            default=d.switch_every,
            help=_("Seconds between mode switches (starts manual)."),
        )
        a(
            "--first-mode",
            choices=(modes.ITO, modes.AUTO),
            default=d.first_mode,
            help=_("Mode to start in; with --switch-every 0 it stays in it."),
        )
        a(
            "--mode-type",
            choices=("bool", "industrial"),
            default=d.mode_type,
            help=_("Message type of the mode."),
        )
        a("--mode-rate", type=float, default=d.mode_rate, help=_("Mode messages per second."))
        a("--gps-rate", type=float, default=d.gps_rate, help=_("GPS fixes per second."))
        a("--tf-rate", type=float, default=d.tf_rate, help=_("Transforms per second."))
        a("--camera-rate", type=float, default=d.camera_rate, help=_("Images per second."))
        a(
            "--camera-size",
            default=f"{d.camera_width}x{d.camera_height}",
            help=_("Image size, WIDTHxHEIGHT."),
        )
        a(
            "--camera-format",
            choices=("raw", "jpeg"),
            default=d.camera_format,
            help=_("raw: sensor_msgs/Image on image; jpeg: CompressedImage on image_compressed."),
        )
        a("--map-size", type=int, default=d.map_size, help=_("Cells per side."))
        a(
            "--map-rate",
            type=float,
            default=d.map_rate,
            help=_("Republish a changed map at this rate (0: once, latched)."),
        )
        a("--prefix", default="", help=_("Topic prefix (robot namespace)."))
        a("--duration", type=float, default=0.0, help=_("Seconds; 0 runs until stopped."))
        a(
            "--open-leg",
            metavar="VEHICLE",
            default="",
            help=_(
                "For demos: make sure this vehicle exists and has an open test event, "
                "shift and leg (created through the services if missing)."
            ),
        )
        a(
            "--wait-for-subscriber",
            type=float,
            default=0.0,
            help=_("Wait up to this many seconds for a GPS subscriber before starting."),
        )

    def handle(self, *args, **o):
        width, height = (int(v) for v in o["camera_size"].lower().split("x"))
        config = SimConfig(
            latitude=o["latitude"],
            longitude=o["longitude"],
            radius=o["radius"],
            speed=o["speed"],
            switch_every=o["switch_every"],
            first_mode=o["first_mode"],
            mode_type=o["mode_type"],
            mode_rate=o["mode_rate"],
            gps_rate=o["gps_rate"],
            tf_rate=o["tf_rate"],
            camera_rate=o["camera_rate"],
            camera_width=width,
            camera_height=height,
            camera_format=o["camera_format"],
            map_size=o["map_size"],
            map_rate=o["map_rate"],
            prefix=o["prefix"],
        )
        if o["open_leg"]:
            self.stdout.write(ensure_open_leg(o["open_leg"]))
        rclpy.init()
        robot = SimulatedRobot(config)
        robot.start(o["wait_for_subscriber"])
        executor = SingleThreadedExecutor()
        executor.add_node(robot)
        self.stdout.write(
            _("simulated robot near %(lat)s, %(lon)s, started at %(t0)s; Ctrl-C stops it")
            % {
                "lat": short(config.latitude),
                "lon": short(config.longitude),
                "t0": number_format(robot.t0, 6),
            }
        )
        end = time.monotonic() + o["duration"] if o["duration"] > 0 else None
        try:
            while rclpy.ok() and (end is None or time.monotonic() < end):
                executor.spin_once(timeout_sec=0.1)
        except (KeyboardInterrupt, ExternalShutdownException):
            pass
        finally:
            self.stdout.write(_("published %(counts)s") % {"counts": robot.counts})
            executor.shutdown()
            robot.destroy_node()
            rclpy.try_shutdown()


def ensure_open_leg(key: str) -> str:
    vehicle, _created = Vehicle.objects.get_or_create(
        key=key, defaults={"short_description": _("Simulated robot (ftt_simulate)")}
    )
    leg = open_leg_for_vehicle(vehicle)
    if leg is None:
        shift = vehicle.shifts.filter(end__isnull=True).first()
        if shift is None:
            event = logs.create_test_event(location=_("Simulation"), version="demo")
            shift = logs.create_shift(test_event=event, vehicle=vehicle)
        leg = logs.create_leg(shift=shift)
    return _("vehicle '%(key)s' logs into %(leg)s of %(shift)s") % {
        "key": key,
        "leg": leg,
        "shift": leg.shift,
    }
