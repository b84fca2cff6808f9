"""Reading a database of the original FTT (fkie/field_test_tool) into this one.

The original is read either live (a PostgreSQL connection string) or from its
plain SQL dump (the file its "download data" button saves), whose COPY blocks
are parsed directly, so no PostgreSQL server is needed for a dump.  Its rows
are turned into archive records (exchange.records) and imported by the
same importer as an FTT archive, with the same rules.

The original has integer ids and no global ones.  Each row gets a uid derived
from its id, its start time and its parent's uid, so reading the same database
(or a later dump of it) again finds the rows imported before and adds nothing.
"""

import base64
import binascii
import io
import re
import uuid
import zoneinfo
from datetime import UTC, datetime
from pathlib import Path

from django.contrib.gis.geos import GEOSException, GEOSGeometry
from django.utils.text import slugify
from PIL import Image as PilImage

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
from telemetry.models import Image

# Fixed, so that uids stay the same from one run (and one installation) to the next.
NAMESPACE = uuid.UUID("6f1e0c52-43a5-4b8e-9a43-0d1c2f7e8b11")
TABLES = (
    "weather",
    "segment_type",
    "ito_reason",
    "personnel",
    "performer",
    "vehicle",
    "pose_source",
    "test_event",
    "shift",
    "leg",
    "segment",
    "note",
    "pose",
    "local_pose",
    "map_image",
    "image",
)
UNKNOWN_VEHICLE = "unknown-vehicle"


class LegacyError(Exception):
    pass


# --- sources ------------------------------------------------------------------------------


class PostgresSource:
    """A live original database; geometry arrives as hex EWKB text, bytea as bytes."""

    def __init__(self, conninfo: str):
        import psycopg2

        try:
            self.connection = psycopg2.connect(conninfo)
        except psycopg2.Error as exc:
            raise LegacyError(f"Cannot connect to the original database: {exc}") from None
        self.connection.set_session(readonly=True)
        self.name = self.connection.dsn

    def rows(self, table: str) -> list[dict]:
        import psycopg2

        with self.connection.cursor() as cursor:
            try:
                cursor.execute(f'SELECT * FROM public."{table}" ORDER BY id')  # noqa: S608
            except psycopg2.Error as exc:
                raise LegacyError(
                    f"The database has no usable table {table}; is it an original FTT "
                    f"database? ({str(exc).strip()})"
                ) from None
            names = [c.name for c in cursor.description]
            return [
                {
                    n: bytes(v) if isinstance(v, memoryview) else v
                    for n, v in zip(names, row, strict=True)
                }
                for row in cursor.fetchall()
            ]

    def close(self):
        self.connection.close()


_COPY = re.compile(r"^COPY (?:public\.)?\"?(\w+)\"? \(([^)]*)\) FROM stdin;$")
_ESCAPES = {"b": "\b", "f": "\f", "n": "\n", "r": "\r", "t": "\t", "v": "\v", "\\": "\\"}
_ESCAPE = re.compile(r"\\(x[0-9a-fA-F]{1,2}|[0-7]{1,3}|.)")


def _copy_value(text: str):
    if text == r"\N":
        return None
    value = _ESCAPE.sub(_unescape, text)
    if value.startswith("\\x") and re.fullmatch(r"\\x[0-9a-fA-F]*", value):
        return bytes.fromhex(value[2:])  # bytea, hex output format
    return value


def _unescape(match: re.Match) -> str:
    token = match.group(1)
    if token in _ESCAPES:
        return _ESCAPES[token]
    if token[0] == "x" and len(token) > 1:
        return chr(int(token[1:], 16))
    if token.isdigit():
        return chr(int(token, 8))
    return token


class DumpSource:
    """A plain-format ``pg_dump`` of an original database (COPY blocks)."""

    def __init__(self, path: str | Path):
        self.name = str(path)
        self.tables: dict[str, list[dict]] = {}
        try:
            with open(path, encoding="utf-8") as handle:
                self._parse(handle)
        except (OSError, UnicodeDecodeError) as exc:
            raise LegacyError(f"Cannot read {path}: {exc}") from None
        if "test_event" not in self.tables:
            raise LegacyError(
                f"{path} holds no COPY data for test_event: it is not a plain pg_dump of an "
                f"original FTT database (a custom-format dump must be restored with "
                f"pg_restore first and read through a connection string)."
            )

    def _parse(self, handle):
        table = columns = None
        for line in handle:
            line = line.rstrip("\n")
            if table is None:
                match = _COPY.match(line)
                if match:
                    table = match.group(1)
                    columns = [c.strip().strip('"') for c in match.group(2).split(",")]
                    self.tables[table] = []
                continue
            if line == "\\.":
                table = None
                continue
            values = [_copy_value(v) for v in line.split("\t")]
            self.tables[table].append(dict(zip(columns, values, strict=True)))

    def rows(self, table: str) -> list[dict]:
        return sorted(self.tables.get(table, []), key=lambda r: int(r["id"]))

    def close(self):
        pass


def open_source(source: str):
    """A path to an existing file is a dump; anything else a connection string."""
    if Path(source).is_file():
        return DumpSource(source)
    return PostgresSource(source)


# --- values -------------------------------------------------------------------------------


def _num(value) -> float | None:
    return None if value is None else float(value)


def _int(value) -> int | None:
    return None if value is None else int(value)


def _time(secs) -> datetime | None:
    return None if secs is None else datetime.fromtimestamp(float(secs), tz=UTC)


def _text(value) -> str:
    return "" if value is None else str(value)


def _fit(value, model, field_name: str) -> str:
    """The original's columns (varchar(512)) are wider than ours; the limit comes
    from the model so that the cut follows it if the model's limit changes."""
    return _text(value)[: model._meta.get_field(field_name).max_length]


def _xy(ewkb) -> tuple[float, float] | None:
    if ewkb is None:
        return None
    try:
        point = GEOSGeometry(ewkb.hex() if isinstance(ewkb, bytes) else ewkb)
    except (GEOSException, ValueError, TypeError):
        raise LegacyError(f"Unreadable geometry value {str(ewkb)[:40]!r}.") from None
    return point.x, point.y


def _uid(parent: uuid.UUID, *parts) -> str:
    return str(uuid.uuid5(parent, ":".join(repr(p) for p in parts)))


def _time_zone(label: str | None) -> str:
    """The original GUI stored labels such as "(UTC+01:00)"; FTT needs IANA names."""
    label = (label or "").strip()
    if label in zoneinfo.available_timezones():
        return label
    match = re.search(r"UTC\s*([+-])(\d{1,2}):?(\d{2})?", label)
    if match and (match.group(3) in (None, "00")):
        hours = int(match.group(2))
        if hours == 0:
            return "UTC"
        # POSIX sign convention: Etc/GMT-1 is one hour ahead of UTC.
        sign = "-" if match.group(1) == "+" else "+"
        return f"Etc/GMT{sign}{hours}"
    return "UTC"


def _key(value, fallback: str, model) -> str:
    return _fit(slugify(value or ""), model, "key") or fallback


def _colour(value, fallback="128,128,128") -> str:
    value = re.sub(r"\s", "", value or "")
    return value if re.fullmatch(r"\d{1,3},\d{1,3},\d{1,3}", value) else fallback


def _decode_base64_text(data: bytes) -> bytes:
    """Images were stored as the base64 text the client sent, inside bytea."""
    if data.startswith((b"\xff\xd8\xff", b"\x89PNG")):
        return data  # already a picture (written by some other tool)
    try:
        return base64.b64decode(data, validate=False)
    except (binascii.Error, ValueError):
        return data


def _as_png(data: bytes) -> bytes:
    with PilImage.open(io.BytesIO(data)) as picture:
        out = io.BytesIO()
        picture.convert("L").save(out, format="PNG")
        return out.getvalue()


# --- conversion ---------------------------------------------------------------------------


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
            raise LegacyError(f"Unexpected content in the original database: {exc!r}") from None

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
        weather = {r["id"]: _key(r["key"], f"weather-{r['id']}", Weather) for r in raw["weather"]}
        types = {
            r["id"]: _key(r["key"], f"type-{r['id']}", SegmentType) for r in raw["segment_type"]
        }
        reasons = {
            r["id"]: _key(r["key"], f"reason-{r['id']}", ItoReason) for r in raw["ito_reason"]
        }
        self._add_catalogue("weather", raw["weather"], weather, Weather)
        self._add_catalogue("segment_types", raw["segment_type"], types, SegmentType)
        self._add_catalogue("ito_reasons", raw["ito_reason"], reasons, ItoReason)
        return weather, types, reasons

    def _add_catalogue(self, table, rows, keys, model):
        for r in rows:
            record = {
                "key": keys[r["id"]],
                "short_description": _fit(r["short_description"], model, "short_description")
                or keys[r["id"]],
                "long_description": _text(r["long_description"]),
            }
            if model is Weather:
                record["icon"] = _fit(r.get("icon_filename"), Weather, "icon")
            else:
                record["color"] = _colour(r.get("color"))
            self.tables[table].append(record)

    def _convert_vehicles(self, rows) -> dict:
        vehicles = {r["id"]: _key(r["key"], f"vehicle-{r['id']}", Vehicle) for r in rows}
        for r in rows:
            self.tables["vehicles"].append(
                {
                    "key": vehicles[r["id"]],
                    "short_description": _fit(r["short_description"], Vehicle, "short_description")
                    or vehicles[r["id"]],
                    "long_description": _text(r["long_description"]),
                    "institution": _fit(r["institution"], Vehicle, "institution"),
                    "configuration": _text(r["configuration"]),
                }
            )
        return vehicles

    def _convert_pose_sources(self, rows) -> dict:
        sources = {r["id"]: _key(r["key"], f"source-{r['id']}", PoseSource) for r in rows}
        for r in rows:
            self.tables["pose_sources"].append(
                {
                    "key": sources[r["id"]],
                    "short_description": _fit(
                        r["short_description"], PoseSource, "short_description"
                    )
                    or sources[r["id"]],
                    "long_description": _text(r["long_description"]),
                }
            )
        return sources

    def _convert_performers(self, rows) -> dict:
        """A performer here is just its institution, so one without is dropped."""
        performers = {}
        for r in rows:
            institution = _text(r["institution"]).strip()
            if institution:
                performers[r["id"]] = _fit(institution, Performer, "institution")
                self.tables["performers"].append({"institution": performers[r["id"]]})
        return performers

    def _convert_personnel(self, rows) -> dict:
        people = {}
        for r in rows:
            people[r["id"]] = f"p{r['id']}"
            self.tables["personnel"].append(
                {
                    "ref": people[r["id"]],
                    "name": _fit(r["name"], Personnel, "name") or f"Person {r['id']}",
                    "institution": _fit(r["institution"], Personnel, "institution"),
                }
            )
        return people

    def _convert_test_events(self, rows) -> tuple[dict, dict]:
        events, event_start = {}, {}
        for r in rows:
            start = _num(r["starttime_secs"])
            if start is None:
                # Every child's uid and fallback start derive from it.
                raise LegacyError(f"test_event {r['id']} has no start time.")
            events[r["id"]] = _uid(NAMESPACE, "test_event", int(r["id"]), start)
            event_start[r["id"]] = start
            self.tables["test_events"].append(
                self._entry(r, events[r["id"]], start)
                | {
                    "location": _fit(r["location"], TestEvent, "location"),
                    "version": _fit(r["version"], TestEvent, "version"),
                    "time_zone": _time_zone(r["time_zone"]),
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
            start = _num(r["starttime_secs"]) or event_start[r["test_event_id"]]
            uid = _uid(uuid.UUID(events[r["test_event_id"]]), "shift", int(r["id"]), start)
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
                "test_intent": _fit(r["test_intent"], Shift, "test_intent"),
                "workspace": _fit(r["workspace"], Shift, "workspace"),
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
            start = _num(r["starttime_secs"]) or shift_start[r["shift_id"]]
            uid = _uid(uuid.UUID(shifts[r["shift_id"]]), "leg", int(r["id"]), start)
            legs[r["id"]], leg_start[r["id"]] = uid, start
            self.tables["legs"].append(
                self._entry(r, uid, start)
                | {
                    "shift": shifts[r["shift_id"]],
                    "number": r["_number"],
                    "weather": weather.get(r["weather_id"]),
                    "default_pose_source": sources.get(r["default_pose_source_id"]),
                    "recording": _fit(r.get("bag_file"), Leg, "recording"),
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
            start = _num(r["starttime_secs"]) or leg_start[r["leg_id"]]
            uid = _uid(uuid.UUID(legs[r["leg_id"]]), "segment", int(r["id"]), start)
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
            if r["segment_id"] not in self.segment_uid or not _text(r["note"]).strip():
                continue
            at = rec.time_out(_time(r["secs"]) or _time(self.segment_start[r["segment_id"]]))
            self.tables["notes"].append(
                {
                    "uid": _uid(uuid.UUID(self.segment_uid[r["segment_id"]]), "note", int(r["id"])),
                    "segment": self.segment_uid[r["segment_id"]],
                    "author": people.get(r["personnel_id"]),
                    "text": _text(r["note"]),
                    "created": at,
                    "edited": at,
                }
            )

    def _convert_poses(self, rows, sources):
        for r in rows:
            if r["segment_id"] not in self.segment_uid or r["position"] is None:
                continue
            seg = self.segment_uid[r["segment_id"]]
            robot = _time(r["orig_secs"])
            self.tables["poses"].append(
                {
                    "uid": _uid(uuid.UUID(seg), "pose", int(r["id"])),
                    "segment": seg,
                    "point": list(_xy(r["position"])),
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
            x, y = _xy(r["position"])
            robot = _time(r["orig_secs"])
            self.tables["local_poses"].append(
                {
                    "uid": _uid(uuid.UUID(seg), "local_pose", int(r["id"])),
                    "segment": seg,
                    "frame": _text(r["frame_id"]).lstrip("/") or "map",
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
            uid = _uid(uuid.UUID(shifts[r["shift_id"]]), "map_image", int(r["id"]))
            try:
                png = _as_png(_decode_base64_text(bytes(r["image_data"])))
            except OSError as exc:
                raise LegacyError(f"map_image {r['id']}: unreadable picture ({exc}).") from None
            name = f"legacy/maps/{uid}.png"
            self.files[name] = png
            origin = _xy(r["origin"]) or (0.0, 0.0)
            robot = _time(r["orig_secs"])
            self.tables["maps"].append(
                {
                    "uid": uid,
                    "shift": shifts[r["shift_id"]],
                    "frame": _text(r["frame_id"]).lstrip("/") or "map",
                    "width": _int(r["width"]),
                    "height": _int(r["height"]),
                    "resolution": _num(r["resolution"]),
                    "origin_x": origin[0],
                    "origin_y": origin[1],
                    "origin_yaw": 0.0,
                    "checksum": "",
                    "robot_stamp": rec.time_out(robot),
                    "received": rec.time_out(_time(r["secs"]) or robot or _time(0)),
                    "file": name,
                }
            )

    def _convert_images(self, rows):
        for r in rows:
            if r["segment_id"] not in self.segment_uid or not r["image_data"]:
                continue
            seg = self.segment_uid[r["segment_id"]]
            uid = _uid(uuid.UUID(seg), "image", int(r["id"]))
            suffix = Path(_text(r["image_filename"])).suffix.lower() or ".jpg"
            name = f"legacy/images/{uid}{suffix}"
            self.files[name] = _decode_base64_text(bytes(r["image_data"]))
            robot = _time(r["orig_secs"])
            self.tables["images"].append(
                {
                    "uid": uid,
                    "segment": seg,
                    "description": _fit(r["description"], Image, "description"),
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
        end = _num(r["endtime_secs"])
        if end is not None:
            end = max(end, start)  # whole-second server clock; never end before start
        return end, rec.time_out(_time(start if end is None else end))

    def _entry(self, r, uid: str, start: float) -> dict:
        end, modified = self._interval(r, start)
        return {
            "uid": uid,
            "modified": modified,
            "start": rec.time_out(_time(start)),
            "end": rec.time_out(_time(end)),
            "note": _text(r.get("note")),
        }

    def _received(self, r, robot):
        return _time(r["secs"]) or robot or _time(self.segment_start[r["segment_id"]])

    @staticmethod
    def _numbered(rows, parent_field):
        """The original numbered by sibling count, which repeats a number after a
        delete; a repeated (or missing) number becomes the next free one."""
        taken: dict = {}
        for r in sorted(rows, key=lambda r: int(r["id"])):
            used = taken.setdefault(r[parent_field], set())
            number = _int(r["number"])
            if number is None or number < 1 or number in used:
                number = max(used, default=0) + 1
            used.add(number)
            yield r | {"_number": number}

    def _segment(self, r, types, reasons, legs, inherit) -> dict:
        """``inherit`` is the master when ``r`` is its first child: the original let
        users annotate an ITO master, FTT keeps reasons on children only, so the
        first child takes over what it lacks."""
        master = r["parent_id"] is None
        annotation = {"ito_reason": None, "obstacle": "", "lighting": "", "slope": ""}
        if not master:
            for name in ("obstacle", "lighting", "slope"):
                annotation[name] = _fit(r[name], Segment, name)
                if inherit is not None and not annotation[name]:
                    annotation[name] = _fit(inherit[name], Segment, name)
            annotation["ito_reason"] = (
                reasons.get(r["ito_reason_id"])
                or (inherit is not None and reasons.get(inherit["ito_reason_id"]))
                or "unassigned"
            )
        position = _xy(r["start_position"])
        local = _xy(r["local_start_position"])
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
            "start": rec.time_out(_time(start)),
            "end": rec.time_out(_time(end)),
            "robot_stamp": rec.time_out(_time(r["orig_starttime_secs"])),
        }
