"""One statement reads tracks within their kept span (PostgreSQL).

The read of tracks (telemetry.storage.postgresql) is bounded by the span
the segments' kept figures give, and the planner prunes the month partitions
only by values it has when it plans: two statements from the client (the
look-up, then the read) in a transaction that keeps JIT off for both.  This
function does the look-up and plans the given read with its results as
parameters ($1 ids, $2 and $3 the span's ends, $4 whether unstamped poses are
read, $5 the figures' mode), with JIT off for its own span: one round trip
instead of four (BEGIN, look-up, read, COMMIT).  Without a mode (NULL) the
span is all time, unstamped poses included.  The figures' table is written
out here so that the migration stays as it is whatever the models later say.
"""

from django.db import migrations

from common.sql import postgresql_only

FORWARD = """
CREATE FUNCTION ftt_read_within_kept_span(query text, ids bigint[], kept_mode text)
RETURNS SETOF record LANGUAGE plpgsql SET jit = off AS $$
DECLARE
    span_first timestamptz := '-infinity';
    span_last timestamptz := 'infinity';
    unstamped boolean := true;
BEGIN
    -- The first time of the usable points (robot clock, else arrival) is at
    -- or before the first robot stamp.  The last point in driving order
    -- carries the latest robot stamp unless it has none (unstamped points
    -- sort last): then the latest time of all is at or after it, and only
    -- then are unstamped poses read (the default partition).
    IF kept_mode IS NOT NULL THEN
        SELECT min(f.first_stamp), max(COALESCE(f.last_robot_stamp, f.last_stamp)),
               COALESCE(bool_or(f.points > 0 AND f.last_robot_stamp IS NULL), false)
          INTO span_first, span_last, unstamped
          FROM telemetry_segmentfigures AS f
         WHERE f.segment_id = ANY(ids) AND f.mode = kept_mode;
    END IF;
    RETURN QUERY EXECUTE query USING ids, span_first, span_last, unstamped, kept_mode;
END $$;
"""

BACKWARD = "DROP FUNCTION ftt_read_within_kept_span(text, bigint[], text);"


class Migration(migrations.Migration):
    dependencies = [
        ("telemetry", "0013_pose_tables_partitioned_by_month"),
    ]

    operations = [postgresql_only(FORWARD, BACKWARD)]
