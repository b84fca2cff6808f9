"""The original database as archive records (exchange.records), for
exchange.importer: the conversion of each table, in order.

The original has integer ids and no global ones.  Each row gets a uid derived
from its id, its start time and its parent's uid, so reading the same database
(or a later dump of it) again finds the rows imported before and adds nothing.
"""

import uuid
from pathlib import Path

from django.core.exceptions import ValidationError
from django.utils.translation import gettext

from events.models import (
    ItoReason,
    Leg,
    Performer,
    Personnel,
    PoseSource,
    Segment,
    SegmentType,
    Shift,
    TestEvent,
    Vehicle,
    Weather,
)
from exchange import records as rec
from exchange.legacy.sources import TABLES, LegacyError
from exchange.legacy.values import (
    catalogue_key,
    decode_picture,
    derived_uid,
    fit,
    iana_zone,
    point_xy,
    rgb_colour,
    to_float,
    to_int,
    to_text,
    to_time,
)
from telemetry.models import Image
from telemetry.pictures import greyscale_png

# Fixed, so that uids stay the same from one run (and one installation) to the next.
NAMESPACE = uuid.UUID("6f1e0c52-43a5-4b8e-9a43-0d1c2f7e8b11")
UNKNOWN_VEHICLE = "unknown-vehicle"


class LegacyBundle:
    """The original database as archive records, for exchange.importer."""

    def __init__(self, source):
        self.source = source
        self.files: dict[str, bytes] = {}
        self.tables: dict[str, list[dict]] = {t: [] for t in rec.TABLES}
        raw = {table: source.rows(table) for table in TABLES}
        try:
            self._convert(raw)
        except (KeyError, TypeError, ValueError) as exc:
            raise LegacyError(
                gettext("Unexpected content in the original database: %(exc)s") % {"exc": repr(exc)}
            ) from None

    def records(self, table: str):
        return iter(self.tables[table])

    def read_file(self, name: str) -> bytes:
        return self.files[name]

    def _convert(self, raw):
        weather, types, reasons = self._convert_catalogues(raw)
        vehicles = self._convert_vehicles(raw["vehicle"])
        sources = self._convert_pose_sources(raw["pose_source"])
        performers = self._convert_performers(raw["performer"])
        people = self._convert_personnel(raw["personnel"])
        events, event_start = self._convert_test_events(raw["test_event"])
        shifts, shift_start = self._convert_shifts(
            raw["shift"], events, event_start, vehicles, performers, people
        )
        legs, leg_start = self._convert_legs(raw["leg"], shifts, shift_start, weather, sources)
        self._convert_segments(raw["segment"], legs, leg_start, types, reasons)
        self._convert_notes(raw["note"], people)
        self._convert_poses(raw["pose"], sources)
        self._convert_local_poses(raw["local_pose"])
        self._convert_maps(raw["map_image"], shifts)
        self._convert_images(raw["image"])

    # Each step returns the maps later steps refer through: original id -> key or
    # uid, and for the log levels also id -> start, which a child without its own
    # start time takes over.

    def _convert_catalogues(self, raw) -> tuple[dict, dict, dict]:
        weather = {
            r["id"]: catalogue_key(r["key"], f"weather-{r['id']}", Weather) for r in raw["weather"]
        }
        types = {
            r["id"]: catalogue_key(r["key"], f"type-{r['id']}", SegmentType)
            for r in raw["segment_type"]
        }
        reasons = {
            r["id"]: catalogue_key(r["key"], f"reason-{r['id']}", ItoReason)
            for r in raw["ito_reason"]
        }
        self._add_catalogue("weather", raw["weather"], weather, Weather)
        self._add_catalogue("segment_types", raw["segment_type"], types, SegmentType)
        self._add_catalogue("ito_reasons", raw["ito_reason"], reasons, ItoReason)
        return weather, types, reasons

    def _add_catalogue(self, table, rows, keys, model):
        for r in rows:
            record = {
                "key": keys[r["id"]],
                "short_description": fit(r["short_description"], model, "short_description")
                or keys[r["id"]],
                "long_description": to_text(r["long_description"]),
            }
            if model is Weather:
                record["icon"] = fit(r.get("icon_filename"), Weather, "icon")
            else:
                record["color"] = rgb_colour(r.get("color"))
            self.tables[table].append(record)

    def _convert_vehicles(self, rows) -> dict:
        vehicles = {r["id"]: catalogue_key(r["key"], f"vehicle-{r['id']}", Vehicle) for r in rows}
        for r in rows:
            self.tables["vehicles"].append(
                {
                    "key": vehicles[r["id"]],
                    "short_description": fit(r["short_description"], Vehicle, "short_description")
                    or vehicles[r["id"]],
                    "long_description": to_text(r["long_description"]),
                    "institution": fit(r["institution"], Vehicle, "institution"),
                    "configuration": to_text(r["configuration"]),
                }
            )
        return vehicles

    def _convert_pose_sources(self, rows) -> dict:
        sources = {r["id"]: catalogue_key(r["key"], f"source-{r['id']}", PoseSource) for r in rows}
        for r in rows:
            self.tables["pose_sources"].append(
                {
                    "key": sources[r["id"]],
                    "short_description": fit(
                        r["short_description"], PoseSource, "short_description"
                    )
                    or sources[r["id"]],
                    "long_description": to_text(r["long_description"]),
                }
            )
        return sources

    def _convert_performers(self, rows) -> dict:
        """A performer here is just its institution, so one without is dropped."""
        performers = {}
        for r in rows:
            institution = to_text(r["institution"]).strip()
            if institution:
                performers[r["id"]] = fit(institution, Performer, "institution")
                self.tables["performers"].append({"institution": performers[r["id"]]})
        return performers

    def _convert_personnel(self, rows) -> dict:
        people = {}
        for r in rows:
            people[r["id"]] = f"p{r['id']}"
            self.tables["personnel"].append(
                {
                    "ref": people[r["id"]],
                    "name": fit(r["name"], Personnel, "name") or f"Person {r['id']}",
                    "institution": fit(r["institution"], Personnel, "institution"),
                }
            )
        return people

    def _convert_test_events(self, rows) -> tuple[dict, dict]:
        events, event_start = {}, {}
        for r in rows:
            start = to_float(r["starttime_secs"])
            if start is None:
                # Every child's uid and fallback start derive from it.
                raise LegacyError(gettext("test_event %(id)s has no start time.") % {"id": r["id"]})
            events[r["id"]] = derived_uid(NAMESPACE, "test_event", int(r["id"]), start)
            event_start[r["id"]] = start
            self.tables["test_events"].append(
                self._entry(r, events[r["id"]], start)
                | {
                    "location": fit(r["location"], TestEvent, "location"),
                    "version": fit(r["version"], TestEvent, "version"),
                    "time_zone": iana_zone(r["time_zone"]),
                }
            )
        return events, event_start

    def _convert_shifts(
        self, rows, events, event_start, vehicles, performers, people
    ) -> tuple[dict, dict]:
        shifts, shift_start = {}, {}
        needs_unknown_vehicle = False
        for r in self._numbered(rows, "test_event_id"):
            if r["test_event_id"] not in events:
                continue  # orphans cannot exist with the original's FKs; be safe anyway
            start = to_float(r["starttime_secs"]) or event_start[r["test_event_id"]]
            uid = derived_uid(uuid.UUID(events[r["test_event_id"]]), "shift", int(r["id"]), start)
            shifts[r["id"]], shift_start[r["id"]] = uid, start
            vehicle = vehicles.get(r["vehicle_id"])
            if vehicle is None:
                # The original allowed a shift without a vehicle; here it is required.
                vehicle, needs_unknown_vehicle = UNKNOWN_VEHICLE, True
            record = self._entry(r, uid, start) | {
                "test_event": events[r["test_event_id"]],
                "number": r["_number"],
                "vehicle": vehicle,
                "performer": performers.get(r["performer_id"]),
                "test_intent": fit(r["test_intent"], Shift, "test_intent"),
                "workspace": fit(r["workspace"], Shift, "workspace"),
            }
            for role in rec.PERSON_ROLES:
                record[role] = people.get(r[f"{role}_id"])
            self.tables["shifts"].append(record)
        if needs_unknown_vehicle:
            self.tables["vehicles"].append(
                {
                    "key": UNKNOWN_VEHICLE,
                    "short_description": "Vehicle not recorded in the original FTT",
                    "long_description": "",
                    "institution": "",
                    "configuration": "",
                }
            )
        return shifts, shift_start

    def _convert_legs(self, rows, shifts, shift_start, weather, sources) -> tuple[dict, dict]:
        legs, leg_start = {}, {}
        for r in self._numbered(rows, "shift_id"):
            if r["shift_id"] not in shifts:
                continue
            start = to_float(r["starttime_secs"]) or shift_start[r["shift_id"]]
            uid = derived_uid(uuid.UUID(shifts[r["shift_id"]]), "leg", int(r["id"]), start)
            legs[r["id"]], leg_start[r["id"]] = uid, start
            self.tables["legs"].append(
                self._entry(r, uid, start)
                | {
                    "shift": shifts[r["shift_id"]],
                    "number": r["_number"],
                    "weather": weather.get(r["weather_id"]),
                    "default_pose_source": sources.get(r["default_pose_source_id"]),
                    "recording": fit(r.get("bag_file"), Leg, "recording"),
                }
            )
        return legs, leg_start

    def _convert_segments(self, rows, legs, leg_start, types, reasons):
        """Fills ``segment_uid`` and ``segment_start``, through which the notes,
        telemetry and images steps find their segment."""
        self.segment_uid, self.segment_start = {}, {}
        masters = [r for r in rows if r["parent_id"] is None]
        children = [r for r in rows if r["parent_id"] is not None]
        master_rows = {r["id"]: r for r in masters}
        first_child = {}
        for r in sorted(children, key=lambda r: int(r["id"])):
            first_child.setdefault(r["parent_id"], r["id"])
        for r in masters + children:
            if r["leg_id"] not in legs:
                continue
            start = to_float(r["starttime_secs"]) or leg_start[r["leg_id"]]
            uid = derived_uid(uuid.UUID(legs[r["leg_id"]]), "segment", int(r["id"]), start)
            self.segment_uid[r["id"]], self.segment_start[r["id"]] = uid, start
        for r in masters + children:
            if r["id"] not in self.segment_uid:
                continue
            inherit = None
            if r["parent_id"] is not None and first_child.get(r["parent_id"]) == r["id"]:
                inherit = master_rows.get(r["parent_id"])
            self.tables["segments"].append(self._segment(r, types, reasons, legs, inherit))

    def _convert_notes(self, rows, people):
        for r in rows:
            if r["segment_id"] not in self.segment_uid or not to_text(r["note"]).strip():
                continue
            at = rec.time_out(to_time(r["secs"]) or to_time(self.segment_start[r["segment_id"]]))
            self.tables["notes"].append(
                {
                    "uid": derived_uid(
                        uuid.UUID(self.segment_uid[r["segment_id"]]), "note", int(r["id"])
                    ),
                    "segment": self.segment_uid[r["segment_id"]],
                    "author": people.get(r["personnel_id"]),
                    "text": to_text(r["note"]),
                    "created": at,
                    "edited": at,
                }
            )

    def _convert_poses(self, rows, sources):
        for r in rows:
            if r["segment_id"] not in self.segment_uid or r["position"] is None:
                continue
            seg = self.segment_uid[r["segment_id"]]
            robot = to_time(r["orig_secs"])
            self.tables["poses"].append(
                {
                    "uid": derived_uid(uuid.UUID(seg), "pose", int(r["id"])),
                    "segment": seg,
                    "point": list(point_xy(r["position"])),
                    "altitude": None,
                    "fix_status": 0,
                    "horizontal_accuracy": None,
                    "pose_source": sources.get(r["pose_source_id"]),
                    "robot_stamp": rec.time_out(robot),
                    "received": rec.time_out(self._received(r, robot)),
                }
            )

    def _convert_local_poses(self, rows):
        for r in rows:
            if r["segment_id"] not in self.segment_uid or r["position"] is None:
                continue
            seg = self.segment_uid[r["segment_id"]]
            x, y = point_xy(r["position"])
            robot = to_time(r["orig_secs"])
            self.tables["local_poses"].append(
                {
                    "uid": derived_uid(uuid.UUID(seg), "local_pose", int(r["id"])),
                    "segment": seg,
                    "frame": to_text(r["frame_id"]).lstrip("/") or "map",
                    "x": x,
                    "y": y,
                    "yaw": None,
                    "robot_stamp": rec.time_out(robot),
                    "received": rec.time_out(self._received(r, robot)),
                }
            )

    def _convert_maps(self, rows, shifts):
        for r in rows:
            if r["shift_id"] not in shifts or not r["image_data"]:
                continue
            uid = derived_uid(uuid.UUID(shifts[r["shift_id"]]), "map_image", int(r["id"]))
            try:
                png = greyscale_png(decode_picture(bytes(r["image_data"])))
            except ValidationError as exc:
                raise LegacyError(
                    gettext("map_image %(id)s: %(error)s")
                    % {"id": r["id"], "error": " ".join(exc.messages)}
                ) from None
            name = f"legacy/maps/{uid}.png"
            self.files[name] = png
            origin = point_xy(r["origin"]) or (0.0, 0.0)
            robot = to_time(r["orig_secs"])
            self.tables["maps"].append(
                {
                    "uid": uid,
                    "shift": shifts[r["shift_id"]],
                    "frame": to_text(r["frame_id"]).lstrip("/") or "map",
                    "width": to_int(r["width"]),
                    "height": to_int(r["height"]),
                    "resolution": to_float(r["resolution"]),
                    "origin_x": origin[0],
                    "origin_y": origin[1],
                    "origin_yaw": 0.0,
                    "checksum": "",
                    "robot_stamp": rec.time_out(robot),
                    "received": rec.time_out(to_time(r["secs"]) or robot or to_time(0)),
                    "file": name,
                }
            )

    def _convert_images(self, rows):
        for r in rows:
            if r["segment_id"] not in self.segment_uid or not r["image_data"]:
                continue
            seg = self.segment_uid[r["segment_id"]]
            uid = derived_uid(uuid.UUID(seg), "image", int(r["id"]))
            suffix = Path(to_text(r["image_filename"])).suffix.lower() or ".jpg"
            name = f"legacy/images/{uid}{suffix}"
            self.files[name] = decode_picture(bytes(r["image_data"]))
            robot = to_time(r["orig_secs"])
            self.tables["images"].append(
                {
                    "uid": uid,
                    "segment": seg,
                    "description": fit(r["description"], Image, "description"),
                    "robot_stamp": rec.time_out(robot),
                    "received": rec.time_out(self._received(r, robot)),
                    "file": name,
                }
            )

    @staticmethod
    def _interval(r, start: float) -> tuple[float | None, str]:
        """The row's end and its stand-in change stamp.  The original keeps no
        change time; its latest known time stands in, so that running the import
        again changes nothing and later edits made here win."""
        end = to_float(r["endtime_secs"])
        if end is not None:
            end = max(end, start)  # whole-second server clock; never end before start
        return end, rec.time_out(to_time(start if end is None else end))

    def _entry(self, r, uid: str, start: float) -> dict:
        end, modified = self._interval(r, start)
        return {
            "uid": uid,
            "modified": modified,
            "start": rec.time_out(to_time(start)),
            "end": rec.time_out(to_time(end)),
            "note": to_text(r.get("note")),
        }

    def _received(self, r, robot):
        return to_time(r["secs"]) or robot or to_time(self.segment_start[r["segment_id"]])

    @staticmethod
    def _numbered(rows, parent_field):
        """The original numbered by sibling count, which repeats a number after a
        delete; a repeated (or missing) number becomes the next free one."""
        taken: dict = {}
        for r in sorted(rows, key=lambda r: int(r["id"])):
            used = taken.setdefault(r[parent_field], set())
            number = to_int(r["number"])
            if number is None or number < 1 or number in used:
                number = max(used, default=0) + 1
            used.add(number)
            yield r | {"_number": number}

    def _segment(self, r, types, reasons, legs, inherit) -> dict:
        """``inherit`` is the master when ``r`` is its first child: the original let
        users annotate an ITO master, FTT keeps reasons on children only, so the
        first child takes over what it lacks."""
        master = r["parent_id"] is None
        annotation = dict(Segment.NO_ANNOTATION)
        if not master:
            for name in ("obstacle", "lighting", "slope"):
                annotation[name] = fit(r[name], Segment, name)
                if inherit is not None and not annotation[name]:
                    annotation[name] = fit(inherit[name], Segment, name)
            annotation["ito_reason"] = (
                reasons.get(r["ito_reason_id"])
                or (inherit is not None and reasons.get(inherit["ito_reason_id"]))
                or "unassigned"
            )
        position = point_xy(r["start_position"])
        local = point_xy(r["local_start_position"])
        start = self.segment_start[r["id"]]
        end, latest = self._interval(r, start)
        return {
            "uid": self.segment_uid[r["id"]],
            "modified": latest,
            "annotated": None if master else latest,
            "leg": legs[r["leg_id"]],
            "parent": None if master else self.segment_uid.get(r["parent_id"]),
            "segment_type": types.get(r["segment_type_id"])
            or (SegmentType.ITO if not master else None),
            **annotation,
            "start_position": list(position) if position else None,
            "start_local_x": local[0] if local else None,
            "start_local_y": local[1] if local else None,
            "start_local_frame": "",
            "start": rec.time_out(to_time(start)),
            "end": rec.time_out(to_time(end)),
            "robot_stamp": rec.time_out(to_time(r["orig_starttime_secs"])),
        }
