"""Reading a database of the original FTT (fkie/field_test_tool) into this one.

The original is read either live (a PostgreSQL connection string) or from its
plain SQL dump (the file its "download data" button saves), whose COPY blocks
are parsed directly, so no PostgreSQL server is needed for a dump.  Its rows
are turned into archive records (events.exchange.records) and imported by the
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

from events.exchange import records as rec
from events.models import SegmentType

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


def _key(value, fallback: str) -> str:
    return slugify(value or "")[:64] or fallback


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
    """The original database as archive records, for events.exchange.importer."""

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
        out = self.tables
        weather = {r["id"]: _key(r["key"], f"weather-{r['id']}") for r in raw["weather"]}
        types = {r["id"]: _key(r["key"], f"type-{r['id']}") for r in raw["segment_type"]}
        reasons = {r["id"]: _key(r["key"], f"reason-{r['id']}") for r in raw["ito_reason"]}
        for table, rows, keys in (
            ("weather", raw["weather"], weather),
            ("segment_types", raw["segment_type"], types),
            ("ito_reasons", raw["ito_reason"], reasons),
        ):
            for r in rows:
                record = {
                    "key": keys[r["id"]],
                    "short_description": _text(r["short_description"])[:128] or keys[r["id"]],
                    "long_description": _text(r["long_description"]),
                }
                if table == "weather":
                    record["icon"] = _text(r.get("icon_filename"))[:64]
                else:
                    record["color"] = _colour(r.get("color"))
                out[table].append(record)

        vehicles = {r["id"]: _key(r["key"], f"vehicle-{r['id']}") for r in raw["vehicle"]}
        for r in raw["vehicle"]:
            out["vehicles"].append(
                {
                    "key": vehicles[r["id"]],
                    "short_description": _text(r["short_description"])[:200] or vehicles[r["id"]],
                    "long_description": _text(r["long_description"]),
                    "institution": _text(r["institution"])[:200],
                    "configuration": _text(r["configuration"]),
                }
            )
        sources = {r["id"]: _key(r["key"], f"source-{r['id']}") for r in raw["pose_source"]}
        for r in raw["pose_source"]:
            out["pose_sources"].append(
                {
                    "key": sources[r["id"]],
                    "short_description": _text(r["short_description"])[:200] or sources[r["id"]],
                    "long_description": _text(r["long_description"]),
                }
            )
        performers = {}
        for r in raw["performer"]:
            if _text(r["institution"]).strip():
                performers[r["id"]] = _text(r["institution"]).strip()[:200]
                out["performers"].append({"institution": performers[r["id"]]})
        people = {}
        for r in raw["personnel"]:
            people[r["id"]] = f"p{r['id']}"
            out["personnel"].append(
                {
                    "ref": people[r["id"]],
                    "name": _text(r["name"])[:200] or f"Person {r['id']}",
                    "institution": _text(r["institution"])[:200],
                }
            )

        events = {}
        event_start = {}
        for r in raw["test_event"]:
            start = _num(r["starttime_secs"])
            if start is None:
                raise LegacyError(f"test_event {r['id']} has no start time.")
            events[r["id"]] = _uid(NAMESPACE, "test_event", int(r["id"]), start)
            event_start[r["id"]] = start
            out["test_events"].append(
                self._entry(r, events[r["id"]], start)
                | {
                    "location": _text(r["location"])[:500],
                    "version": _text(r["version"])[:200],
                    "time_zone": _time_zone(r["time_zone"]),
                }
            )

        shifts, shift_start = {}, {}
        needs_unknown_vehicle = False
        for r in self._numbered(raw["shift"], "test_event_id"):
            if r["test_event_id"] not in events:
                continue  # orphans cannot exist with the original's FKs; be safe anyway
            start = _num(r["starttime_secs"]) or event_start[r["test_event_id"]]
            uid = _uid(uuid.UUID(events[r["test_event_id"]]), "shift", int(r["id"]), start)
            shifts[r["id"]], shift_start[r["id"]] = uid, start
            vehicle = vehicles.get(r["vehicle_id"])
            if vehicle is None:
                vehicle, needs_unknown_vehicle = UNKNOWN_VEHICLE, True
            record = self._entry(r, uid, start) | {
                "test_event": events[r["test_event_id"]],
                "number": r["_number"],
                "vehicle": vehicle,
                "performer": performers.get(r["performer_id"]),
                "test_intent": _text(r["test_intent"])[:500],
                "workspace": _text(r["workspace"])[:500],
            }
            for role in rec.PERSON_ROLES:
                record[role] = people.get(r[f"{role}_id"])
            out["shifts"].append(record)
        if needs_unknown_vehicle:
            out["vehicles"].append(
                {
                    "key": UNKNOWN_VEHICLE,
                    "short_description": "Vehicle not recorded in the original FTT",
                    "long_description": "",
                    "institution": "",
                    "configuration": "",
                }
            )

        legs, leg_start = {}, {}
        for r in self._numbered(raw["leg"], "shift_id"):
            if r["shift_id"] not in shifts:
                continue
            start = _num(r["starttime_secs"]) or shift_start[r["shift_id"]]
            uid = _uid(uuid.UUID(shifts[r["shift_id"]]), "leg", int(r["id"]), start)
            legs[r["id"]], leg_start[r["id"]] = uid, start
            out["legs"].append(
                self._entry(r, uid, start)
                | {
                    "shift": shifts[r["shift_id"]],
                    "number": r["_number"],
                    "weather": weather.get(r["weather_id"]),
                    "default_pose_source": sources.get(r["default_pose_source_id"]),
                    "recording": _text(r.get("bag_file"))[:500],
                }
            )

        self.segment_uid, self.segment_start = {}, {}
        masters = [r for r in raw["segment"] if r["parent_id"] is None]
        children = [r for r in raw["segment"] if r["parent_id"] is not None]
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
            out["segments"].append(self._segment(r, types, reasons, legs, inherit))

        for r in raw["note"]:
            if r["segment_id"] not in self.segment_uid or not _text(r["note"]).strip():
                continue
            at = rec.time_out(_time(r["secs"]) or _time(self.segment_start[r["segment_id"]]))
            out["notes"].append(
                {
                    "uid": _uid(uuid.UUID(self.segment_uid[r["segment_id"]]), "note", int(r["id"])),
                    "segment": self.segment_uid[r["segment_id"]],
                    "author": people.get(r["personnel_id"]),
                    "text": _text(r["note"]),
                    "created": at,
                    "edited": at,
                }
            )
        for r in raw["pose"]:
            if r["segment_id"] not in self.segment_uid or r["position"] is None:
                continue
            seg = self.segment_uid[r["segment_id"]]
            robot = _time(r["orig_secs"])
            out["poses"].append(
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
        for r in raw["local_pose"]:
            if r["segment_id"] not in self.segment_uid or r["position"] is None:
                continue
            seg = self.segment_uid[r["segment_id"]]
            x, y = _xy(r["position"])
            robot = _time(r["orig_secs"])
            out["local_poses"].append(
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
        for r in raw["map_image"]:
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
            out["maps"].append(
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
        for r in raw["image"]:
            if r["segment_id"] not in self.segment_uid or not r["image_data"]:
                continue
            seg = self.segment_uid[r["segment_id"]]
            uid = _uid(uuid.UUID(seg), "image", int(r["id"]))
            suffix = Path(_text(r["image_filename"])).suffix.lower() or ".jpg"
            name = f"legacy/images/{uid}{suffix}"
            self.files[name] = _decode_base64_text(bytes(r["image_data"]))
            robot = _time(r["orig_secs"])
            out["images"].append(
                {
                    "uid": uid,
                    "segment": seg,
                    "description": _text(r["description"])[:500],
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
                annotation[name] = _text(r[name])[:500]
                if inherit is not None and not annotation[name]:
                    annotation[name] = _text(inherit[name])[:500]
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
