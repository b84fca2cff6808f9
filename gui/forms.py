"""The GUI's dialogs as the server defines them: each field's name, label,
kind, whether it is required, its help text and its choices, read from the
REST API's serializers, so the page never declares a field again."""

import zoneinfo

from django.utils.text import capfirst
from rest_framework import serializers
from rest_framework.fields import empty

from events.api.serializers import LegSerializer, ShiftSerializer, TestEventSerializer
from events.selectors.logs import missing_for_new, new_entry_values
from events.services import logs
from reports.api.serializers import ReportFormSerializer

LEVELS = {
    "event": (TestEventSerializer, logs.TEST_EVENT_FIELDS),
    "shift": (ShiftSerializer, logs.SHIFT_FIELDS),
    "leg": (LegSerializer, logs.LEG_FIELDS),
}
# Typed values get suggestions, not a fixed list: the server checks what is typed.
SUGGESTIONS = {"time_zone": lambda: ["UTC", *sorted(zoneinfo.available_timezones() - {"UTC"})]}


def field_description(name: str, field: serializers.Field, choices: dict) -> dict:
    """One field, JSON-ready; ``choices`` keeps each model's rows (four people, one read)."""
    label = field.label or name.replace("_", " ").capitalize()
    description = {
        "name": name,
        "label": str(label),
        "help": str(field.help_text or ""),
        "required": bool(field.required and not getattr(field, "allow_null", False)),
        "type": "text",
        "choices": None,
        "max_length": getattr(field, "max_length", None),
    }
    if isinstance(field, serializers.ChoiceField):
        description["type"] = "select"
        description["choices"] = [[value, str(text)] for value, text in field.choices.items()]
    elif isinstance(field, serializers.FloatField | serializers.IntegerField):
        description["type"] = "number"
    elif isinstance(field, serializers.RelatedField):
        description["type"] = "select"
        queryset = field.get_queryset()
        model = queryset.model
        if model not in choices:
            # Catalogue words are stored lower case ("sunny"); a list shows them as words.
            choices[model] = [[obj.pk, capfirst(str(obj))] for obj in queryset]
        description["choices"] = choices[model]
    elif field.style.get("base_template") == "textarea.html":
        description["type"] = "textarea"
    if name in SUGGESTIONS:
        description["suggestions"] = SUGGESTIONS[name]()
    return description


def report_form() -> dict:
    fields = ReportFormSerializer().fields
    return {
        "fields": [field_description(name, field, {}) for name, field in fields.items()],
        "initial": {
            name: field.initial
            for name, field in fields.items()
            # Only real defaults: blank text fields start empty anyway.
            if field.initial not in (None, "") and field.initial is not empty
        },
        "unavailable": "",
    }


def gui_forms(person, test_event_id: int | None = None) -> dict:
    """Every dialog of the page; log levels with what a new entry starts with."""
    return {**log_forms(person, test_event_id), "report": report_form()}


def log_forms(person, test_event_id: int | None = None) -> dict:
    """The dialogs of test events, shifts and legs, with what a new one starts with.
    With a test event, a leg's test cases are that event's only (the ones the
    server accepts for its legs)."""
    forms, choices = {}, {}
    for level, (serializer_class, names) in LEVELS.items():
        fields = serializer_class().fields
        if level == "leg" and test_event_id is not None:
            field = fields["test_case"]
            field.queryset = field.get_queryset().filter(test_event_id=test_event_id)
        forms[level] = {
            "fields": [field_description(name, fields[name], choices) for name in names],
            "initial": new_entry_values(level, person),
            "unavailable": missing_for_new(level),
        }
    return forms
