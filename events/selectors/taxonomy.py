"""Which take-over reasons a test event's figures use, and the history of a row.

An open (or closed, not yet final) event uses the catalogue as it is now; a
final event uses the copy frozen when it was finalised
(``TestEvent.taxonomy``), so editing the catalogue never changes its figures.
"""

from events.models import ItoReason, TestEvent


def current_taxonomy() -> dict[str, dict]:
    """{reason key: {"name", "color", "counts"}} of the catalogue now."""
    return {
        r.key: {"name": r.short_description, "color": r.color, "counts": r.counts_as_intervention}
        for r in ItoReason.objects.order_by("key")
    }


def taxonomy_of(event: TestEvent) -> dict[str, dict]:
    return event.taxonomy if event.taxonomy is not None else current_taxonomy()


def taxonomy_version(event: TestEvent) -> str:
    """Names the taxonomy a report used: frozen at finalisation, or the live catalogue."""
    if event.taxonomy is not None and event.finalised is not None:
        return f"frozen {event.finalised:%Y-%m-%d %H:%M:%S} UTC"
    return "current catalogue"


def counted_reasons(event: TestEvent) -> set[str]:
    """The rule "counts as intervention", as it applies to this event."""
    return {key for key, entry in taxonomy_of(event).items() if entry["counts"]}
