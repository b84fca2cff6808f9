"""Import a robot recording: ``manage.py ftt_import_bag BAG --vehicle KEY [--leg ID|UID]``."""

import json
import sys
import uuid
from pathlib import Path

import yaml
from django.core.management.base import BaseCommand, CommandError
from django.db.models import Q
from django.utils.translation import gettext as _
from django.utils.translation import gettext_noop

from common.progress import ProgressBar
from events.models import Leg, TestEvent, Vehicle
from exchange.bag import BagImportError, import_bag
from rosbridge_app.collector.modes import MODE_TYPES
from rosbridge_app.collector.params import NODE_NAME, SPECS, read_file

PHASES = {"reading": gettext_noop("Reading messages"), "storing": gettext_noop("Storing events")}


def _pairs(values: list[str], prefix: str) -> dict:
    out = {}
    for item in values or []:
        name, sep, raw = item.partition("=")
        if not sep:
            raise CommandError(_("'%(item)s' is not NAME=VALUE.") % {"item": item})
        try:
            value = json.loads(raw)
        except ValueError:
            value = raw
        out[name if name.startswith(prefix) else prefix + name] = value
    return out


def _lookup(model, ident: str | None):
    if ident is None:
        return None
    try:
        lookup = Q(pk=int(ident)) if ident.isdigit() else Q(uid=uuid.UUID(ident))
        return model.objects.get(lookup)
    except (model.DoesNotExist, ValueError):
        raise CommandError(
            _("No %(kind)s with id or uid '%(ident)s'.")
            % {"kind": model._meta.verbose_name, "ident": ident}
        ) from None


class Command(BaseCommand):
    help = _(
        "Import a ROS 1 bag or a ROS 2 bag (sqlite3 or mcap) with the live collector's rules: "
        "segments from the mode topic, GPS and local poses, maps and camera images. Without "
        "--leg a new test event, shift and leg spanning the recording are made. Importing "
        "the same bag again adds nothing."
    )

    def add_arguments(self, parser):
        parser.add_argument("bag", help=_("A .bag file, or a ROS 2 bag directory / .db3 / .mcap."))
        parser.add_argument("--vehicle", required=True, help=_("Key of the vehicle that recorded."))
        parser.add_argument("--leg", help=_("Open leg (id or uid) to log into."))
        parser.add_argument("--test-event", help=_("Open test event for the new shift."))
        parser.add_argument(
            "--mode-type",
            choices=MODE_TYPES,
            help=_("Type of the mode topic (collector default: bool)."),
        )
        parser.add_argument(
            "--topic",
            action="append",
            metavar="NAME=TOPIC",
            help=_("Topic name as for the collector, e.g. robot_mode=/mode or gps_fix=/fix."),
        )
        parser.add_argument(
            "--params-file",
            metavar="FILE",
            help=_(
                "The robot's ftt_collect parameters file (ROS 2 YAML, as given to "
                "ftt_collect --params-file); --topic and --param override it."
            ),
        )
        parser.add_argument(
            "--param",
            action="append",
            metavar="NAME=VALUE",
            help=_("Collector parameter, e.g. pose_min_distance=1.0 or use_tf=false."),
        )
        parser.add_argument(
            "--snapshots",
            action="store_true",
            help=_(
                "Also cut the black box's window around every take-over into an MCAP "
                "file on its ITO segment, as the live collector does."
            ),
        )
        parser.add_argument(
            "--snapshot",
            action="append",
            metavar="NAME=VALUE",
            help=_("Snapshot parameter, e.g. before=30, after=5 or topics=/fix,/odom."),
        )

    def handle(
        self,
        *args,
        bag,
        vehicle,
        leg,
        test_event,
        mode_type,
        topic,
        param,
        snapshot,
        params_file,
        **options,
    ):
        try:
            vehicle_row = Vehicle.objects.get(key=vehicle)
        except Vehicle.DoesNotExist:
            raise CommandError(
                _("No vehicle with key '%(vehicle)s'.") % {"vehicle": vehicle}
            ) from None
        params = self._from_file(params_file) if params_file else {}
        params |= (
            _pairs(topic, "topics.") | _pairs(param, "params.") | _pairs(snapshot, "snapshot.")
        )
        if mode_type:
            params["params.robot_mode_type"] = mode_type
        self.stderr.write(_("Importing %(bag)s") % {"bag": bag})
        bar = ProgressBar(options.get("stderr") or sys.stderr)
        try:
            result = import_bag(
                bag,
                vehicle=vehicle_row,
                leg=_lookup(Leg, leg),
                test_event=_lookup(TestEvent, test_event),
                params=params,
                progress=lambda phase, done, total: bar.count(
                    f"{_(PHASES[phase]):<16}", done, total
                ),
                snapshots=options["snapshots"],
            )
        except BagImportError as exc:
            raise CommandError(str(exc)) from None
        masters = result.leg.segments.masters().count()
        added = ", ".join(f"{n} {name}" for name, n in result.added.items())
        self.stdout.write(
            _(
                "%(events)s events from the bag into %(leg)s of %(shift)s (%(event)s): "
                "%(masters)s master segments in the leg; added %(added)s; %(skipped)s "
                "event(s) stored nothing (already there, or outside an open segment)."
            )
            % {
                "events": result.events,
                "leg": result.leg,
                "shift": result.leg.shift,
                "event": result.leg.shift.test_event,
                "masters": masters,
                "added": added,
                "skipped": result.skipped,
            }
        )

    def _from_file(self, path: str) -> dict:
        try:
            values = read_file(Path(path))
        except (OSError, yaml.YAMLError) as exc:
            raise CommandError(
                _("Cannot read parameters file %(file)s: %(exc)s") % {"file": path, "exc": exc}
            ) from None
        if not values:
            raise CommandError(
                _("%(file)s has no ros__parameters for %(node)s (nor for /**).")
                % {"file": path, "node": NODE_NAME}
            )
        # A robot's file may set ROS's own parameters (use_sim_time, …) too.
        if ignored := sorted(name for name in values if name not in SPECS):
            self.stderr.write(
                _("Not collector parameters, ignored: %(names)s") % {"names": ", ".join(ignored)}
            )
        return {name: value for name, value in values.items() if name in SPECS}
