import django.db.models.deletion
from django.db import migrations, models

# Only the indexes go; Django's own AlterField would also drop and re-add the
# foreign keys, which re-checks every stored pose on a large table.
INDEXES = [
    ("telemetry_pose_segment_id_6d29dff0", "telemetry_pose", "segment_id"),
    ("telemetry_pose_pose_source_id_6cf467bd", "telemetry_pose", "pose_source_id"),
    ("telemetry_localpose_segment_id_165bcea0", "telemetry_localpose", "segment_id"),
]


class Migration(migrations.Migration):
    dependencies = [
        ("events", "0007_robot_accounts"),
        ("telemetry", "0003_recording"),
    ]

    operations = [
        migrations.SeparateDatabaseAndState(
            database_operations=[
                migrations.RunSQL(
                    f'DROP INDEX IF EXISTS "{name}"',
                    reverse_sql=f'CREATE INDEX "{name}" ON "{table}" ("{column}")',
                )
                for name, table, column in INDEXES
            ],
            state_operations=[
                migrations.AlterField(
                    model_name="localpose",
                    name="segment",
                    field=models.ForeignKey(
                        db_index=False,
                        on_delete=django.db.models.deletion.CASCADE,
                        related_name="local_poses",
                        to="events.segment",
                    ),
                ),
                migrations.AlterField(
                    model_name="pose",
                    name="pose_source",
                    field=models.ForeignKey(
                        blank=True,
                        db_index=False,
                        null=True,
                        on_delete=django.db.models.deletion.PROTECT,
                        related_name="poses",
                        to="events.posesource",
                    ),
                ),
                migrations.AlterField(
                    model_name="pose",
                    name="segment",
                    field=models.ForeignKey(
                        db_index=False,
                        on_delete=django.db.models.deletion.CASCADE,
                        related_name="poses",
                        to="events.segment",
                    ),
                ),
            ],
        ),
    ]
