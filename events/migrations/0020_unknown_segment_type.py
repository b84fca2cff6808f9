"""The segment type of what the collector logged before the robot said its mode."""

from django.db import migrations

from events import seeds


def add_unknown(apps, schema_editor):
    SegmentType = apps.get_model("events", "SegmentType")
    for key, short, long, color in seeds.SEGMENT_TYPES:
        if key == "unknown":
            SegmentType.objects.get_or_create(
                key=key,
                defaults={"short_description": short, "long_description": long, "color": color},
            )


def remove_unknown(apps, schema_editor):
    apps.get_model("events", "SegmentType").objects.filter(key="unknown").delete()


class Migration(migrations.Migration):
    dependencies = [
        ("events", "0019_test_plan_labels_translated"),
    ]

    operations = [
        migrations.RunPython(add_unknown, remove_unknown),
    ]
