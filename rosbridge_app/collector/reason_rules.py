"""Reasons the robot knows: rules that suggest a take-over's reason; free of ROS.

``params.reason_rules`` holds a small YAML document::

    window: 2.0                 # s before a switch to ITO a signal counts
    rules:
      - {topic: /estop, type: std_msgs/msg/Bool, field: data, values: [true], reason: safety}
      - {topic: /planner/status, type: my_msgs/msg/Status, field: planner.level,
         values: [3], reason: planner}
      - {topic: /localization/pose, type: geometry_msgs/msg/PoseStamped,
         silent: 1.0, reason: other}    # silent for 1 s at the switch

At a switch to ITO the first rule in the list that fired (a value that holds
at the switch or began within ``window`` before it, or a topic silent for
``silent`` seconds after having been heard) gives the take-over its *suggested* reason; the operator
confirms or changes it (the reason itself stays unassigned until then).
"""

from collections.abc import Callable
from dataclasses import dataclass
from datetime import datetime

from django.utils.translation import gettext as _

from rosbridge_app.collector.mode_sources import (
    InvalidModeSources,
    Source,
    check_path,
    field_value,
    load_entries,
    matchers,
    matches,
    parse_path,
)

_KEYS = {"topic", "type", "field", "values", "silent", "reason"}


@dataclass(frozen=True)
class Rule:
    topic: str
    type: str
    reason: str
    path: tuple = ()
    values: tuple = ()
    silent: float | None = None


@dataclass(frozen=True)
class ReasonRules:
    window: float
    rules: tuple[Rule, ...]


def parse(text: str, fields_of: Callable[[str], dict] | None = None) -> ReasonRules | None:
    """The rules of ``params.reason_rules`` (None when empty), or
    InvalidModeSources naming what is wrong."""
    loaded = load_entries(text, "rules", _KEYS)
    if loaded is None:
        return None
    data, entries = loaded
    window = data.get("window", 2.0)
    if isinstance(window, bool) or not isinstance(window, int | float) or not 0 <= window <= 60:
        raise InvalidModeSources(_("window must be 0–60 s"))
    rules = []
    for n, raw, topic, typename in entries:
        reason = str(raw.get("reason") or "")
        if not reason:
            raise InvalidModeSources(_("rule %(n)d has no reason") % {"n": n})
        silent = raw.get("silent")
        if silent is not None:
            if isinstance(silent, bool) or not isinstance(silent, int | float) or silent <= 0:
                raise InvalidModeSources(_("rule %(n)d: silent is seconds > 0") % {"n": n})
            rule = Rule(topic, typename, reason, silent=float(silent))
        else:
            path_text = str(raw.get("field") or "")
            values = matchers("values", n, raw.get("values"))
            if not values:
                raise InvalidModeSources(
                    _("rule %(n)d needs values (with field) or silent") % {"n": n}
                )
            rule = Rule(topic, typename, reason, parse_path(path_text), values)
            if fields_of is not None:
                probe = Source(topic, typename, rule.path, (), (), text=path_text)
                check_path(probe, fields_of)
        rules.append(rule)
    return ReasonRules(float(window), tuple(rules))


class ReasonWatcher:
    """What the rules saw, and the reason they suggest at a switch."""

    def __init__(self, config: ReasonRules):
        self.config = config
        # When each value rule's signal began (None: not since it last ended),
        # and whether it still holds: a signal that began within the window or
        # still holds at the switch counts; one that began earlier and ended does not.
        self.began: list[datetime | None] = [None] * len(config.rules)
        self.holds: list[bool] = [False] * len(config.rules)
        self.heard: list[datetime | None] = [None] * len(config.rules)

    def topics(self) -> dict[str, str]:
        """{topic: type} the rules listen to."""
        return {r.topic: r.type for r in self.config.rules}

    def offer(self, topic: str, msg, at: datetime) -> None:
        for i, rule in enumerate(self.config.rules):
            if rule.topic.lstrip("/") != topic.lstrip("/"):
                continue
            self.heard[i] = at
            if rule.silent is None:
                try:
                    value = field_value(msg, rule.path)
                except (IndexError, AttributeError):
                    continue
                holds = any(matches(m, value) for m in rule.values)
                if holds and not self.holds[i]:
                    self.began[i] = at
                self.holds[i] = holds

    def reason_at(self, at: datetime) -> str | None:
        for i, rule in enumerate(self.config.rules):
            if rule.silent is not None:
                heard = self.heard[i]
                if heard is not None and (at - heard).total_seconds() >= rule.silent:
                    return rule.reason
                continue
            began = self.began[i]
            if began is None:
                continue
            if self.holds[i] or 0 <= (at - began).total_seconds() <= self.config.window:
                return rule.reason
        return None
