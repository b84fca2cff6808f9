"""Where the pose tables keep their rows.

On PostgreSQL each pose table (GPS and local) is partitioned by month of the
robot's stamp (UTC): an index covers one month, an old month can be detached,
archived or moved to cheaper storage, and a campaign that fills whole months is
dropped with them.  Poses without a robot stamp, or in a month without a
partition yet, go to the table's default partition; ``ensure_partitions``
(daily, ``manage.py ftt_pose_storage``) makes the coming months' partitions and
moves such months out of the default partition.  SpatiaLite keeps one table;
``ensure_partitions`` is a no-op there (``storage.is_partitioned``), and the
migration steps run on PostgreSQL only.

A uid is unique per partition (``UNIQUE (uid)`` on each), not across them: a
global unique index is what partitioning avoids (it would grow with every pose
and be paid by every insert).  A re-sent pose carries its stamp, so it meets
its first copy in the same partition and is skipped by the inserts'
``ON CONFLICT DO NOTHING``.  A uid re-used with another stamp in the same month
is skipped as well; in another month it is stored as a second pose.
docs/architecture.md ("Pose storage") says why.
"""

from datetime import UTC, datetime

from django.db import connection, transaction

from telemetry import storage
from telemetry.models import LocalPose, Pose

TABLES = (Pose._meta.db_table, LocalPose._meta.db_table)
KEY = "robot_stamp"
# Partitions made ahead of the current month, so the daily job can miss a few days.
MONTHS_AHEAD = 2


def _month(value: datetime) -> datetime:
    value = value.astimezone(UTC)
    return datetime(value.year, value.month, 1, tzinfo=UTC)


def _next(month: datetime) -> datetime:
    return month.replace(year=month.year + month.month // 12, month=month.month % 12 + 1)


def months_between(first: datetime, last: datetime) -> list[datetime]:
    """The first instants (UTC) of every month from ``first``'s to ``last``'s."""
    month, end, months = _month(first), _month(last), []
    while month <= end:
        months.append(month)
        month = _next(month)
    return months


def partition_name(table: str, month: datetime) -> str:
    return f"{table}_{month:%Y%m}"


def _default(table: str) -> str:
    return f"{table}_default"


def _existing(cursor, table: str) -> set[str]:
    cursor.execute(
        "SELECT c.relname FROM pg_inherits i JOIN pg_class c ON c.oid = i.inhrelid "
        "WHERE i.inhparent = %s::regclass",
        [table],
    )
    return {name for (name,) in cursor.fetchall()}


def _months_in_default(cursor, table: str) -> list[datetime]:
    cursor.execute(
        f"SELECT DISTINCT date_trunc('month', {KEY}, 'UTC') FROM {_default(table)} "
        f"WHERE {KEY} IS NOT NULL"
    )
    return [row[0] for row in cursor.fetchall()]


def _add_partition(cursor, table: str, name: str) -> None:
    """``name`` (a table of the parent's shape) attached as a partition, with its uid key."""
    cursor.execute(f"ALTER TABLE {name} ADD CONSTRAINT {name}_uid_key UNIQUE (uid)")


def _create_month(cursor, table: str, month: datetime) -> None:
    name, default = partition_name(table, month), _default(table)
    bounds = f"FROM ('{month.isoformat()}') TO ('{_next(month).isoformat()}')"
    within = f"{KEY} >= %s AND {KEY} < %s"
    cursor.execute(f"SELECT EXISTS (SELECT 1 FROM {default} WHERE {within})", [month, _next(month)])
    if not cursor.fetchone()[0]:
        cursor.execute(f"CREATE TABLE {name} PARTITION OF {table} FOR VALUES {bounds}")
        _add_partition(cursor, table, name)
        return
    # The default partition holds poses of this month (an import, a robot's
    # clock): they move into the new partition, which PostgreSQL cannot attach
    # while the default one still has them.
    cursor.execute(f"ALTER TABLE {table} DETACH PARTITION {default}")
    cursor.execute(f"CREATE TABLE {name} PARTITION OF {table} FOR VALUES {bounds}")
    _add_partition(cursor, table, name)
    cursor.execute(
        f"WITH moved AS (DELETE FROM {default} WHERE {within} RETURNING *) "
        f"INSERT INTO {table} SELECT * FROM moved",
        [month, _next(month)],
    )
    cursor.execute(f"ALTER TABLE {table} ATTACH PARTITION {default} DEFAULT")


def ensure_partitions(first: datetime | None = None, last: datetime | None = None) -> list[str]:
    """Make the partitions of every pose table for the months from ``first`` to
    ``last`` (both optional), the current month and ``MONTHS_AHEAD`` after it,
    and each month the default partition holds; returns the new partitions."""
    now = _month(datetime.now(UTC))
    ahead = now
    for _ in range(MONTHS_AHEAD):
        ahead = _next(ahead)
    wanted = set(months_between(now, ahead))
    if first is not None:
        wanted.update(months_between(first, last or first))
    made = []
    for table in TABLES:
        if not storage.is_partitioned(table):
            continue
        with transaction.atomic(), connection.cursor() as cursor:
            existing = _existing(cursor, table)
            for month in sorted(wanted | set(_months_in_default(cursor, table))):
                if partition_name(table, month) not in existing:
                    _create_month(cursor, table, month)
                    made.append(partition_name(table, month))
    return made


def _definitions(cursor, table: str) -> tuple[list[str], list[str]]:
    """The table's own indexes but its keys (CREATE INDEX statements) and its
    foreign keys (ALTER TABLE statements), to make them again on a new table."""
    cursor.execute(
        "SELECT pg_get_indexdef(i.indexrelid) FROM pg_index i "
        "WHERE i.indrelid = %s::regclass AND NOT i.indisunique",
        [table],
    )
    # A partitioned table's own index reads "ON ONLY"; made again, it is to reach
    # the partitions too.
    indexes = [row[0].replace(" ON ONLY ", " ON ") for row in cursor.fetchall()]
    cursor.execute(
        "SELECT conname, pg_get_constraintdef(oid) FROM pg_constraint "
        "WHERE conrelid = %s::regclass AND contype = 'f'",
        [table],
    )
    keys = [f"ALTER TABLE {table} ADD CONSTRAINT {name} {d}" for name, d in cursor.fetchall()]
    return indexes, keys


def _move_rows(cursor, table: str, old: str, select: str) -> None:
    """Rows of ``old`` into ``table`` (same columns), ids kept; ``old`` dropped,
    and the identity sequence goes on from the largest id under its own name."""
    cursor.execute(f"INSERT INTO {table} {select}")
    cursor.execute(f"DROP TABLE {old}")
    cursor.execute("SELECT pg_get_serial_sequence(%s, 'id')", [table])
    sequence = cursor.fetchone()[0]
    cursor.execute(
        f"SELECT setval(%s, coalesce((SELECT max(id) FROM {table}), 0) + 1, false)", [sequence]
    )
    cursor.execute(f"ALTER SEQUENCE {sequence} RENAME TO {table}_id_seq")


def partition_table(table: str) -> None:
    """Turn the plain pose table ``table`` into the partitioned one, rows, ids,
    indexes and foreign keys kept (a migration's forward step)."""
    old = f"{table}_unpartitioned"
    with connection.cursor() as cursor:
        indexes, keys = _definitions(cursor, table)
        cursor.execute(f"ALTER TABLE {table} RENAME TO {old}")
        cursor.execute(
            f"CREATE TABLE {table} (LIKE {old} INCLUDING DEFAULTS INCLUDING IDENTITY) "
            f"PARTITION BY RANGE ({KEY})"
        )
        cursor.execute(f"CREATE TABLE {_default(table)} PARTITION OF {table} DEFAULT")
        _add_partition(cursor, table, _default(table))
        cursor.execute(
            f"SELECT DISTINCT date_trunc('month', {KEY}, 'UTC') FROM {old} WHERE {KEY} IS NOT NULL"
        )
        for (month,) in sorted(cursor.fetchall()):
            name = partition_name(table, month)
            cursor.execute(
                f"CREATE TABLE {name} PARTITION OF {table} FOR VALUES "
                f"FROM ('{month.isoformat()}') TO ('{_next(month).isoformat()}')"
            )
            _add_partition(cursor, table, name)
        # Indexes are built after the rows, at once (their names are free again).
        _move_rows(cursor, table, old, f"SELECT * FROM {old}")
        for statement in indexes + keys:
            cursor.execute(statement)


def merge_table(table: str) -> None:
    """Turn the partitioned pose table back into one plain table (the
    migration's backward step).  Of poses sharing a uid (one re-used in
    another month) the first stored stays: the plain table's uid is unique."""
    old = f"{table}_partitioned"
    with connection.cursor() as cursor:
        indexes, keys = _definitions(cursor, table)
        cursor.execute(f"ALTER TABLE {table} RENAME TO {old}")
        cursor.execute(f"CREATE TABLE {table} (LIKE {old} INCLUDING DEFAULTS INCLUDING IDENTITY)")
        _move_rows(cursor, table, old, f"SELECT DISTINCT ON (uid) * FROM {old} ORDER BY uid, id")
        cursor.execute(f"ALTER TABLE {table} ADD CONSTRAINT {table}_pkey PRIMARY KEY (id)")
        cursor.execute(f"ALTER TABLE {table} ADD CONSTRAINT {table}_uid_key UNIQUE (uid)")
        for statement in indexes + keys:
            cursor.execute(statement)
