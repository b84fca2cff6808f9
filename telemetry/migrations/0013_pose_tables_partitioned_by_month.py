"""The pose tables partitioned by month of the robot's stamp on PostgreSQL
(telemetry.services.pose_partitions); SpatiaLite keeps one table.  The pose
models do not change: the partitions are storage, not schema Django knows."""

from django.db import migrations


def partition(apps, schema_editor):
    if schema_editor.connection.vendor != "postgresql":
        return
    from telemetry.services import pose_partitions

    for table in pose_partitions.TABLES:
        pose_partitions.partition_table(table)
    pose_partitions.ensure_partitions()


def merge(apps, schema_editor):
    if schema_editor.connection.vendor != "postgresql":
        return
    from telemetry.services import pose_partitions

    for table in pose_partitions.TABLES:
        pose_partitions.merge_table(table)


class Migration(migrations.Migration):
    dependencies = [
        ("telemetry", "0012_thinned_segments"),
    ]

    operations = [migrations.RunPython(partition, merge)]
