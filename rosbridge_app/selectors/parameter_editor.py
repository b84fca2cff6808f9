"""The collector's parameters as the cockpit's editor shows them: each with its
schema, the topics that fit it and, for the mode sources, the presets to start
from. The collector itself never loads this (the presets are the command's and
the editor's)."""

from django.utils.translation import gettext as _

from rosbridge_app.collector.mode_presets import PRESETS
from rosbridge_app.collector.params import SPECS, expected_types
from rosbridge_app.models import Collector

MODE_SOURCES = "params.mode_sources"


def _presets_of(name: str) -> list[dict]:
    """The documents the editor offers to start a parameter from."""
    if name != MODE_SOURCES:
        return []
    return [{"name": p.name, "summary": str(p.summary), "document": p.document} for p in PRESETS]


def parameter_rows(collector: Collector) -> list[dict]:
    """The collector's parameters as the editor shows them, from the schema."""
    values = collector.parameters or {}
    topics = collector.topics or []
    rows = []
    for name in sorted(values):
        spec = SPECS.get(name)
        expected = expected_types(name, values)
        rows.append(
            {
                "name": name,
                "value": values[name],
                "type": spec.kind if spec else type(values[name]).__name__,
                "description": _(spec.description) if spec else "",
                "minimum": spec.minimum if spec else None,
                "maximum": spec.maximum if spec else None,
                "choices": list(spec.choices) if spec and spec.choices else None,
                "multiline": bool(spec and spec.multiline),
                "expects": list(expected),
                "suggestions": sorted(
                    t["name"] for t in topics if set(t.get("types", ())) & set(expected)
                ),
                "presets": _presets_of(name),
            }
        )
    return rows
