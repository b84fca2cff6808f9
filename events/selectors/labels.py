"""What a segment is called: the same words in the GUI, the report, the CSV and the API.

Master segments are numbered per leg in driving order (start, then id), so
the numbers stay readable however many legs a test event has: "Leg 2 · #7".
An ITO reason (child) is numbered under its master: "Leg 2 · #7.1".  The
database id stays a technical detail.

The database numbers them (``_NUMBERED``, window functions that PostgreSQL and
SQLite share), so a label costs its own row, not a read of its whole leg.  The
masters' window reads the partial index ``segment_master_order`` in its own
order; only the numbers of the chosen segments' masters leave the window.
"""

from django.core.exceptions import EmptyResultSet
from django.db import connection
from django.db.models import QuerySet
from django.utils.translation import gettext as _
from django.utils.translation import gettext_noop

from events.models import Leg, Segment

_NUMBERED = """
WITH chosen AS (
    SELECT id, leg_id, parent_id, {master_id} AS master_id FROM {segment} WHERE id IN ({chosen})
),
masters AS (
    SELECT id, n FROM (
        SELECT id, ROW_NUMBER() OVER (PARTITION BY leg_id ORDER BY start, id) AS n
        FROM {segment}
        WHERE {master} AND leg_id IN (SELECT leg_id FROM chosen)
    ) numbered
    WHERE id IN (SELECT master_id FROM chosen)
),
children AS (
    SELECT id, ROW_NUMBER() OVER (PARTITION BY parent_id ORDER BY start, id) AS n
    FROM {segment}
    WHERE parent_id IN (SELECT parent_id FROM chosen)
)
SELECT chosen.id, leg.number, master.n, child.n
FROM chosen
JOIN {leg} leg ON leg.id = chosen.leg_id
LEFT JOIN masters master ON master.id = chosen.master_id
LEFT JOIN children child ON child.id = chosen.id
"""


def numbers_of(segments: QuerySet) -> dict[int, tuple[int, str]]:
    """{segment id: (its leg's number, its number "7" or "7.1")} for the segments
    of a queryset, each numbered among every segment of its leg; one query."""
    try:
        chosen, params = segments.order_by().values("id").query.sql_with_params()
    except EmptyResultSet:  # a filter that can match nothing (pk__in=[])
        return {}
    sql = _NUMBERED.format(
        segment=Segment._meta.db_table,
        leg=Leg._meta.db_table,
        chosen=chosen,
        master=Segment.MASTER_SQL,
        master_id=Segment.MASTER_ID_SQL,
    )
    with connection.cursor() as cursor:
        cursor.execute(sql, params)
        return {pk: (leg, _number(master, child)) for pk, leg, master, child in cursor.fetchall()}


def _number(master: int | None, child: int | None) -> str:
    own = "?" if master is None else str(master)
    return own if child is None else f"{own}.{child}"


def leg_numbers(leg_id: int) -> dict[int, str]:
    """{segment id: "7" or "7.1"} for every segment of one leg."""
    return {pk: n for pk, (_leg, n) in numbers_of(Segment.objects.filter(leg_id=leg_id)).items()}


def legs_numbers(leg_ids) -> dict[int, tuple[int, str]]:
    """{segment id: (its leg's number, its number)} for every segment of the given
    legs, in one query."""
    return numbers_of(Segment.objects.filter(leg_id__in=leg_ids))


_LABEL = gettext_noop("Leg %(leg)s · %(segment)s")


def label(leg_number: int, number: str) -> str:
    return _(_LABEL) % {"leg": leg_number, "segment": short_label(number)}


def short_label(number: str) -> str:
    """The label within its leg, where the leg is plain: "#7.1"."""
    return f"#{number}"


def segment_label(segment: Segment) -> str:
    """The label of one segment (one query)."""
    leg_number, number = numbers_of(Segment.objects.filter(pk=segment.pk))[segment.pk]
    return label(leg_number, number)


def segment_labels(segments: QuerySet) -> dict[int, str]:
    """{segment id: "Leg 2 · #7"} for the segments of a queryset; one query."""
    template = _(_LABEL)  # translated once, not per segment
    return {
        pk: template % {"leg": leg_number, "segment": short_label(number)}
        for pk, (leg_number, number) in numbers_of(segments).items()
    }
