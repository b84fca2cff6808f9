"""The change history of one row, as people read it (API, GUI dialog, reports)."""

from django.core.exceptions import FieldDoesNotExist
from django.utils.translation import gettext as _
from django.utils.translation import gettext_noop

KINDS = {"+": "created", "~": "changed", "-": "deleted"}
# What a reader sees for each kind and channel (events.models.changes.CHANNELS).
WORDS = {
    "created": gettext_noop("created"),
    "changed": gettext_noop("changed"),
    "deleted": gettext_noop("deleted"),
    "gui": "GUI",
    "api": "API",
    "legacy": gettext_noop("original robots' API"),
    "admin": gettext_noop("admin"),
    "collector": gettext_noop("collector"),
    "import": gettext_noop("import"),
    "system": gettext_noop("system"),
}


def word_for(value: str) -> str:
    """What a reader sees for a kind ("deleted") or channel ("admin"), translated."""
    return _(WORDS[value]) if value in WORDS else value


def _field_name(model, field: str) -> str:
    try:
        return str(model._meta.get_field(field).verbose_name)
    except FieldDoesNotExist:
        return field


def author_of(entry) -> str:
    """The account that made the change here, or, for an entry another
    installation recorded, the name it gave with that installation's name: a
    name that only looks like an account here never reads as that account."""
    user = entry.history_user
    if user is not None:
        return user.get_username()
    if entry.history_source:
        return _("%(author)s (at %(installation)s)") % {
            "author": entry.history_author or _("FTT"),
            "installation": entry.history_source,
        }
    return entry.history_author


def _value(value) -> str | None:
    return None if value is None else str(value)


def describe_entry(entry, previous) -> dict:
    changes = []
    if previous is not None:
        delta = entry.diff_against(previous, foreign_keys_are_objs=False)
        changes = [
            {
                "field": c.field,
                "field_name": _field_name(entry.instance_type, c.field),
                "before": _value(c.old),
                "after": _value(c.new),
            }
            for c in delta.changes
            if c.field != "modified"
        ]
    return {
        "at": entry.history_date.isoformat(),
        "kind": KINDS[entry.history_type],
        "kind_text": word_for(KINDS[entry.history_type]),
        "author": author_of(entry) or _("FTT"),
        "channel": entry.history_channel,
        "channel_text": word_for(entry.history_channel),
        "reason": entry.history_change_reason or "",
        "imported_from": entry.history_source or None,
        "changes": changes,
    }


def history_of(instance) -> list[dict]:
    """Newest first: who changed the row, when, through what, why, before → after."""
    # By time, not by id: rows an import brings are added after the import's own.
    entries = list(
        instance.history.select_related("history_user").order_by("history_date", "history_id")
    )
    described = [
        describe_entry(entry, entries[i - 1] if i else None) for i, entry in enumerate(entries)
    ]
    return described[::-1]


def entries_since(model, since, **filters) -> list:
    """History rows of ``model`` (a tracked model) changed after ``since``."""
    return list(
        model.history.filter(history_date__gt=since, **filters)
        .select_related("history_user")
        .order_by("history_date", "history_id")
    )
