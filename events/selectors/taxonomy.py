"""Which take-over reasons a test event's figures use, and the history of a row.

An open (or closed, not yet final) event uses the catalogue as it is now; a
final event uses the copy frozen when it was finalised
(``TestEvent.taxonomy``), so editing the catalogue never changes its figures.
"""

from django.utils.translation import gettext as _

from events.models import ItoReason, TestEvent


def current_taxonomy() -> dict[str, dict]:
    """{reason key: {"name", "color", "counts"}} of the catalogue now."""
    return {
        r.key: {"name": r.short_description, "color": r.color, "counts": r.counts_as_intervention}
        for r in ItoReason.objects.order_by("key")
    }


def taxonomy_of(event: TestEvent) -> dict[str, dict]:
    return taxonomies_of([event])[event.pk]


def taxonomies_of(events) -> dict[int, dict[str, dict]]:
    """{event id: its taxonomy}, the live catalogue read at most once."""
    current = None
    found = {}
    for event in events:
        if event.taxonomy is None and current is None:
            current = current_taxonomy()
        found[event.pk] = event.taxonomy if event.taxonomy is not None else current
    return found


def taxonomy_version(event: TestEvent) -> str:
    """Names the taxonomy a report used: frozen at finalisation, or the live catalogue."""
    if event.taxonomy is not None and event.finalised is not None:
        return f"frozen {event.finalised:%Y-%m-%d %H:%M:%S} UTC"
    return "current catalogue"


def taxonomy_text(event: TestEvent) -> str:
    """``taxonomy_version`` as its reader writes it (the PDF's provenance)."""
    if event.taxonomy is not None and event.finalised is not None:
        return _("frozen %(when)s UTC") % {"when": f"{event.finalised:%Y-%m-%d %H:%M:%S}"}
    return _("current catalogue")


def counted_reasons(event: TestEvent) -> set[str]:
    """The rule "counts as intervention", as it applies to this event."""
    return counted_reasons_of([event])[event.pk]


def counted_reasons_of(events) -> dict[int, set[str]]:
    """{event id: ``counted_reasons``} of many events (the catalogue read once)."""
    return {
        pk: {key for key, entry in taxonomy.items() if entry["counts"]}
        for pk, taxonomy in taxonomies_of(events).items()
    }
