"""The figures keep the uid sum of their segment's poses (common.uid_sums), so a
report's data digest reads no pose.  Every kept figures row takes the sum of
its poses (a thinned master: of the poses left), in one pass over the poses;
a master with poses and no figures yet (a database from before 0007, which
leaves the measuring here) is measured whole.  Both use today's figures code,
which matches the table only from here on."""

from django.db import migrations, models

CHUNK = 200


def measure_stored_tracks(apps, schema_editor):
    from telemetry.services.segment_figures import recount_figures, sum_uids_again

    Segment = apps.get_model("events", "Segment")
    SegmentFigures = apps.get_model("telemetry", "SegmentFigures")
    kept = set(SegmentFigures.objects.values_list("segment_id", flat=True))
    if kept:
        sum_uids_again()
    masters = Segment.objects.filter(parent__isnull=True).order_by("pk")
    ids = [pk for pk in masters.values_list("pk", flat=True) if pk not in kept]
    for begin in range(0, len(ids), CHUNK):
        recount_figures(ids[begin : begin + CHUNK], fix=True)


class Migration(migrations.Migration):
    dependencies = [
        ("telemetry", "0014_tracks_read_in_one_statement"),
    ]

    operations = [
        migrations.AddField(
            model_name="segmentfigures",
            name="uid_sum",
            field=models.CharField(db_default="0" * 64, default="0" * 64, max_length=64),
        ),
        migrations.RunPython(measure_stored_tracks, migrations.RunPython.noop),
    ]
