"""manage.py ftt_collect: log a robot's ROS 2 topics into FTT (docs/collector.md)."""

import argparse
from pathlib import Path

from django.core.management.base import BaseCommand
from django.utils.translation import gettext as _

from rosbridge_app.collector.params import DEFAULT_FILE
from rosbridge_app.collector.runtime import CollectorRuntime


class Command(BaseCommand):
    help = _("Record robot mode, positions, map and camera from ROS 2 into the open leg.")
    # The system checks load every URL, view and admin module: seconds of a
    # collector's start-up for nothing it uses (migrate and the server run them).
    requires_system_checks = []

    def add_arguments(self, parser):
        parser.add_argument("--vehicle", default="", help=_("Vehicle key (else the parameter)."))
        parser.add_argument(
            "--params-file",
            type=Path,
            default=DEFAULT_FILE,
            help=_("ROS parameters YAML; /save_ftt_params writes back to it."),
        )
        parser.add_argument(
            "--name",
            default=None,
            help=_("Collector name shown in the GUI (default host/vehicle)."),
        )
        parser.add_argument(
            "--spool",
            type=Path,
            default=None,
            help=_("Local spool file (default $FTT_DATA_DIR/collector/)."),
        )
        parser.add_argument(
            "--start-logging",
            action="store_true",
            help=_("Log from the start (else as left last time, or off)."),
        )
        parser.add_argument(
            "--ros-args",
            nargs=argparse.REMAINDER,
            default=[],
            dest="ros_args",
            help=_("Last option: everything after it goes to rclpy (e.g. -r __ns:=/robot1)."),
        )

    def handle(self, *args, **opts):
        params_file = opts["params_file"]
        ros_args = list(opts["ros_args"])
        if params_file is not None:
            if not params_file.exists():
                raise SystemExit(
                    _("Parameters file %(file)s does not exist.") % {"file": params_file}
                )
            ros_args = ["--params-file", str(params_file), *ros_args]
        runtime = CollectorRuntime(
            vehicle=opts["vehicle"],
            params_file=params_file,
            name=opts["name"],
            spool=opts["spool"],
            start_logging=opts["start_logging"],
        )
        raise SystemExit(runtime.run(ros_args))
