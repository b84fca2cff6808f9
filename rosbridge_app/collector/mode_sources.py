"""Mode from any topic: mode sources, their checks and how they combine; free of ROS.

``params.mode_sources`` holds a small YAML document (docs/collector.md has the
presets)::

    rule: any_ito            # or: first
    sources:
      - topic: /mavros/state
        type: mavros_msgs/msg/State
        field: mode            # a path: state.autonomy.level, buttons[4]
        auto: [OFFBOARD, AUTO.MISSION]
        ito: [MANUAL, POSCTL, {min: 10, max: 20}]
        default: unknown       # auto, ito or unknown for any other value
        hysteresis: 0.5        # s a new value must hold before it counts
        stamp: header.stamp    # the robot's time of the value (the default where
                               # the type has a header; else the DDS send time)

Combination rules (the one place they are decided):

* ``any_ito``: ITO as soon as any source says ITO (an e-stop source maps
  "pressed" to ITO and nothing else, so it only ever vetoes); else AUTO if a
  source says AUTO; else unknown;
* ``first``: the first source, in the listed order, that says something.

Several sources may read fields of one message (a status message's level
and the e-stop inside it): each message is offered to every source of its topic.

While the combination is unknown the last known mode stays (a silent or
"says nothing" source never opens a segment by itself).
"""

import re
from collections.abc import Callable
from dataclasses import dataclass, field
from datetime import datetime, timedelta
from typing import NamedTuple

import yaml
from django.utils.translation import gettext as _

from rosbridge_app.collector.mode_timing import HEADER_STAMP, ModeClock, stamp_of
from rosbridge_app.collector.modes import AUTO, ITO

RULES = ("any_ito", "first")
DEFAULTS = (AUTO, ITO, "unknown")
TYPE_NAME = re.compile(r"^[A-Za-z][\w]*/msg/[A-Za-z][\w]*$")
_STEP = re.compile(r"([A-Za-z_]\w*)((?:\[\d+\])*)")
_KEYS = {"topic", "type", "field", "auto", "ito", "default", "hysteresis", "stamp"}
TIME_TYPE = "builtin_interfaces/msg/Time"
# Entries (sources, rules) and values of one mapping a document may have: far
# more than a robot names, few enough that checking and applying stay quick.
MAX_ENTRIES = 100


class InvalidModeSources(ValueError):
    pass


@dataclass(frozen=True)
class Range:
    minimum: float | None
    maximum: float | None

    def __contains__(self, value) -> bool:
        if isinstance(value, bool) or not isinstance(value, int | float):
            return False
        low = self.minimum is None or value >= self.minimum
        return low and (self.maximum is None or value <= self.maximum)


@dataclass(frozen=True)
class Source:
    topic: str
    type: str
    path: tuple  # field names (str) and indices (int)
    auto: tuple
    ito: tuple
    default: str = "unknown"
    hysteresis: float = 0.0
    text: str = ""  # the field path as written, for messages
    stamp: tuple = HEADER_STAMP  # path of the robot's time of the value

    def mode_of(self, value) -> str | None:
        """'auto', 'ito' or None (the source says nothing) for a field value."""
        for mode, matchers in ((ITO, self.ito), (AUTO, self.auto)):
            if any(matches(m, value) for m in matchers):
                return mode
        return None if self.default == "unknown" else self.default


class Switch(NamedTuple):
    """A change of the combined mode: when, and how it was timed (mode_timing.py)."""

    mode: str
    at: datetime
    robot_stamp: datetime | None = None
    uncertainty: float | None = None


@dataclass(frozen=True)
class ModeSources:
    rule: str
    sources: tuple[Source, ...] = field(default=())

    def by_topic(self) -> dict[str, tuple[int, ...]]:
        """{topic: the numbers of its sources}: one subscription per topic, each
        message offered to every source that reads a field of it."""
        found: dict[str, tuple[int, ...]] = {}
        for i, source in enumerate(self.sources):
            topic = source.topic.lstrip("/")
            found[topic] = found.get(topic, ()) + (i,)
        return found


def matches(matcher, value) -> bool:
    if isinstance(matcher, Range):
        return value in matcher
    if isinstance(matcher, bool) or isinstance(value, bool):
        return isinstance(matcher, bool) and isinstance(value, bool) and matcher == value
    if isinstance(matcher, int | float) and isinstance(value, int | float):
        return matcher == value
    return str(matcher) == str(value)


def parse_path(text: str) -> tuple:
    """``state.autonomy.level`` → ("state", "autonomy", "level"), ``buttons[4]`` → ("buttons", 4)"""
    parts: list = []
    for step in str(text).split("."):
        m = _STEP.fullmatch(step)
        if not m:
            raise InvalidModeSources(_("field path %(path)r is not valid") % {"path": text})
        parts.append(m.group(1))
        parts += [int(i) for i in re.findall(r"\d+", m.group(2))]
    return tuple(parts)


def field_value(msg, path: tuple):
    """The value at ``path`` in a message (rclpy or rosbags), as a plain Python value."""
    value = msg
    for step in path:
        value = value[step] if isinstance(step, int) else getattr(value, step)
    if hasattr(value, "item"):  # numpy scalars of rosbags messages
        value = value.item()
    if isinstance(value, bytes) and len(value) == 1:  # rclpy byte/char fields
        value = value[0]
    return value


def matchers(name: str, index: int, raw) -> tuple:
    if raw is None:
        return ()
    items = raw if isinstance(raw, list) else [raw]
    if len(items) > MAX_ENTRIES:
        raise InvalidModeSources(
            _("source %(n)d: %(key)s has more than %(limit)d values")
            % {"n": index, "key": name, "limit": MAX_ENTRIES}
        )
    out = []
    for item in items:
        if isinstance(item, dict):
            unknown = set(item) - {"min", "max"}
            bounds = [item.get("min"), item.get("max")]
            if unknown or not any(b is not None for b in bounds):
                raise InvalidModeSources(
                    _("source %(n)d: a range in %(key)s is {min: …, max: …}")
                    % {"n": index, "key": name}
                )
            if any(b is not None and not isinstance(b, int | float) for b in bounds):
                raise InvalidModeSources(
                    _("source %(n)d: range bounds in %(key)s must be numbers")
                    % {"n": index, "key": name}
                )
            out.append(Range(*bounds))
        elif isinstance(item, str | int | float | bool):
            out.append(item)
        else:
            raise InvalidModeSources(
                _("source %(n)d: %(key)s takes values, lists of values and ranges")
                % {"n": index, "key": name}
            )
    return tuple(out)


def load_entries(text: str, key: str, allowed: set) -> tuple[dict, list] | None:
    """The YAML document of a parameter and its entries under ``key``, each
    (number, mapping, topic, type) with only ``allowed`` keys, a topic and a
    type; None when the text is empty."""
    if not str(text or "").strip():
        return None
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        raise InvalidModeSources(_("not valid YAML: %(error)s") % {"error": exc}) from None
    except RecursionError:
        # PyYAML builds nested lists and mappings by recursion.
        raise InvalidModeSources(_("not valid YAML: nested too deeply")) from None
    if not isinstance(data, dict) or not isinstance(data.get(key), list):
        raise InvalidModeSources(_("expected '%(key)s:' with a list") % {"key": key})
    if len(data[key]) > MAX_ENTRIES:
        # YAML aliases repeat an entry for a few characters each.
        raise InvalidModeSources(
            _("%(key)s has more than %(limit)d entries") % {"key": key, "limit": MAX_ENTRIES}
        )
    entries = []
    for n, raw in enumerate(data[key], start=1):
        where = {"n": n, "key": key}
        if not isinstance(raw, dict):
            raise InvalidModeSources(_("%(key)s entry %(n)d is not a mapping") % where)
        extra = sorted(set(raw) - allowed)
        if extra:
            raise InvalidModeSources(
                _("%(key)s entry %(n)d: unknown keys %(keys)s")
                % {**where, "keys": ", ".join(extra)}
            )
        topic, typename = str(raw.get("topic") or ""), str(raw.get("type") or "")
        if not topic:
            raise InvalidModeSources(_("%(key)s entry %(n)d has no topic") % where)
        if not TYPE_NAME.match(typename):
            raise InvalidModeSources(
                _("%(key)s entry %(n)d: type %(type)r is not package/msg/Name")
                % {**where, "type": typename}
            )
        entries.append((n, raw, topic, typename))
    return data, entries


def parse(text: str, fields_of: Callable[[str], dict] | None = None) -> ModeSources | None:
    """The mode sources of ``params.mode_sources`` (None when empty: the classic
    ``topics.robot_mode``), or InvalidModeSources naming what is wrong.

    ``fields_of(type)`` ({field: kind}, see message_fields.py) checks each
    field path against its type; it raises KeyError for an unknown type."""
    loaded = load_entries(text, "sources", _KEYS)
    if loaded is None:
        return None
    data, entries = loaded
    rule = data.get("rule", "any_ito")
    if rule not in RULES:
        raise InvalidModeSources(_("rule must be one of %(rules)s") % {"rules": ", ".join(RULES)})
    sources = []
    for n, raw, topic, typename in entries:
        path_text = str(raw.get("field") or "")
        path = parse_path(path_text)
        default = raw.get("default", "unknown")
        if default not in DEFAULTS:
            raise InvalidModeSources(
                _("source %(n)d: default must be auto, ito or unknown") % {"n": n}
            )
        hysteresis = raw.get("hysteresis", 0.0)
        if isinstance(hysteresis, bool) or not isinstance(hysteresis, int | float):
            raise InvalidModeSources(_("source %(n)d: hysteresis is seconds") % {"n": n})
        if not 0 <= hysteresis <= 60:
            raise InvalidModeSources(_("source %(n)d: hysteresis must be 0–60 s") % {"n": n})
        source = Source(
            topic=topic,
            type=typename,
            path=path,
            auto=matchers("auto", n, raw.get("auto")),
            ito=matchers("ito", n, raw.get("ito")),
            default=default,
            hysteresis=float(hysteresis),
            text=path_text,
            stamp=parse_path(raw["stamp"]) if raw.get("stamp") else HEADER_STAMP,
        )
        if not source.auto and not source.ito and default == "unknown":
            raise InvalidModeSources(_("source %(n)d maps no value to auto or ito") % {"n": n})
        if fields_of is not None:
            check_values(source, n, check_path(source, fields_of))
            if raw.get("stamp"):
                check_path(source, fields_of, source.stamp, str(raw["stamp"]), TIME_TYPE)
        sources.append(source)
    if not sources:
        raise InvalidModeSources(_("sources is empty"))
    types: dict[str, str] = {}
    for source in sources:
        # Several sources may read fields of one message; one topic has one type.
        first = types.setdefault(source.topic.lstrip("/"), source.type)
        if first != source.type:
            raise InvalidModeSources(
                _("topic %(topic)s: its sources name two types, %(first)s and %(type)s")
                % {"topic": source.topic, "first": first, "type": source.type}
            )
    return ModeSources(rule, tuple(sources))


def check_path(
    source: Source,
    fields_of: Callable[[str], dict],
    path: tuple | None = None,
    text: str | None = None,
    ends_at: str | None = None,
) -> None:
    """InvalidModeSources naming the type or field that does not exist.
    ``path`` (written ``text``) is the value's field unless given; it ends at a
    single value, or at a message of type ``ends_at``."""
    path, text = (source.path, source.text) if path is None else (path, text)
    typename = source.type
    kind: tuple = ("msg", typename)
    for step in path:
        if isinstance(step, int):
            if kind[0] != "array":
                raise InvalidModeSources(
                    _("%(type)s: %(path)s indexes a field that is not an array")
                    % {"type": source.type, "path": text}
                )
            kind = kind[1]
            continue
        if kind[0] != "msg":
            raise InvalidModeSources(
                _("%(type)s: %(path)s goes into a field that is not a message")
                % {"type": source.type, "path": text}
            )
        try:
            fields = fields_of(kind[1])
        except KeyError:
            raise InvalidModeSources(
                _(
                    "unknown message type %(type)s: not installed in FTT's environment "
                    "(docs/collector.md: custom message types)"
                )
                % {"type": kind[1]}
            ) from None
        if step not in fields:
            raise InvalidModeSources(
                _("%(type)s has no field %(field)s (it has %(fields)s)")
                % {"type": kind[1], "field": step, "fields": ", ".join(fields) or "none"}
            )
        kind = fields[step]
    if ends_at is not None and kind != ("msg", ends_at):
        raise InvalidModeSources(
            _("%(type)s: %(path)s is not a time stamp (%(time)s)")
            % {"type": source.type, "path": text, "time": ends_at}
        )
    if ends_at is None and kind[0] != "base":
        raise InvalidModeSources(
            _("%(type)s: %(path)s is not a single value") % {"type": source.type, "path": text}
        )
    return kind


_TEXT_TYPES = {"string", "wstring"}
_BOOL_TYPES = {"bool", "boolean"}


def check_values(source: Source, index: int, kind: tuple) -> None:
    """InvalidModeSources for a value of ``auto``/``ito`` that the field's
    type (``kind``, a base kind) can never hold: a mapping that never matches
    would lose every switch it was meant to see."""
    base = kind[1]
    for name, values in (("auto", source.auto), ("ito", source.ito)):
        for value in values:
            if base in _TEXT_TYPES:
                fits = isinstance(value, str | int | float) and not isinstance(value, bool)
            elif base in _BOOL_TYPES:
                fits = isinstance(value, bool)
            else:
                fits = isinstance(value, Range) or (
                    isinstance(value, int | float) and not isinstance(value, bool)
                )
            if fits:
                continue
            where = {"n": index, "key": name, "path": source.text, "base": base}
            if isinstance(value, bool) and base in _TEXT_TYPES:
                # YAML 1.1 reads ON, OFF, yes, no, true and false unquoted as booleans.
                raise InvalidModeSources(
                    _(
                        "source %(n)d: %(key)s has a boolean for %(path)s (%(base)s); YAML "
                        "reads ON, OFF, yes and no as booleans: put the text in quotes"
                    )
                    % where
                )
            raise InvalidModeSources(
                _("source %(n)d: %(key)s value %(value)s can never match %(path)s (%(base)s)")
                % {**where, "value": "{min, max}" if isinstance(value, Range) else repr(value)}
            )


class Combiner:
    """The mode the sources say together, with each source's hysteresis."""

    def __init__(self, config: ModeSources):
        self.config = config
        n = len(config.sources)
        self.confirmed: list[str | None] = [None] * n  # confirmed, per source
        # (mode, since, robot stamp, uncertainty) of a value within its hysteresis
        self.pending: list[tuple | None] = [None] * n
        self.clocks = [ModeClock() for _ in range(n)]
        self.mode: str | None = None

    def offer(
        self, index: int, msg, at: datetime, sent: datetime | None = None
    ) -> list[Switch] | None:
        """Each change of the combined mode this message, received at ``at``
        and sent at ``sent`` (if known), causes; None for a second copy of a
        message already offered."""
        source = self.config.sources[index]
        try:
            mode, missing = source.mode_of(field_value(msg, source.path)), False
        except (IndexError, AttributeError):
            mode, missing = None, True  # buttons[4] of a joystick with three buttons
        placed = self.clocks[index].place(mode, stamp_of(msg, source.stamp), sent, at)
        if placed is None:
            return None
        if missing:
            return []  # says nothing
        start, stamp, uncertainty = placed
        if not source.hysteresis:
            self.confirmed[index], self.pending[index] = mode, None
            return self._combine(Switch(mode, start, stamp, uncertainty))
        if mode == self.confirmed[index]:
            self.pending[index] = None  # a flicker shorter than the hysteresis
            return []
        pending = self.pending[index]
        if pending is None or pending[0] != mode:
            self.pending[index] = (mode, start, stamp, uncertainty)
        return self.tick(at)

    def tick(self, at: datetime) -> list[Switch]:
        """Confirm values that held for their source's hysteresis; the switch
        happens when the hysteresis ran out, not when it was noticed."""
        changes = []
        due = []
        for i, pending in enumerate(self.pending):
            if pending is None:
                continue
            mode, since, stamp, uncertainty = pending
            held = timedelta(seconds=self.config.sources[i].hysteresis)
            if since + held <= at:
                robot_stamp = stamp + held if stamp is not None else None
                due.append((i, Switch(mode, since + held, robot_stamp, uncertainty)))
        for i, switch in sorted(due, key=lambda d: d[1].at):
            self.confirmed[i], self.pending[i] = switch.mode, None
            changes += self._combine(switch)
        return changes

    def _combine(self, switch: Switch) -> list[Switch]:
        confirmed = self.confirmed
        if self.config.rule == "first":
            mode = next((m for m in confirmed if m is not None), None)
        elif ITO in confirmed:
            mode = ITO
        else:
            mode = AUTO if AUTO in confirmed else None
        if mode is None or mode == self.mode:
            return []
        self.mode = mode
        return [switch._replace(mode=mode)]
