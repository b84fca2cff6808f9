"""Seed the catalogues of the original tool (same keys and colours, so data
moves between installations) and create the three role groups."""

from django.db import migrations

from events import seeds

# The migration calls the live module on purpose: a fresh install and a test
# database that was flushed must hold the same catalogues.


def seed(apps, schema_editor):
    seeds.seed_catalogues(apps)


def roles(apps, schema_editor):
    seeds.create_roles(apps)


class Migration(migrations.Migration):
    dependencies = [
        ("events", "0001_initial"),
        ("telemetry", "0001_initial"),
        ("auth", "0012_alter_user_first_name_max_length"),
        ("contenttypes", "0002_remove_content_type_name"),
    ]

    operations = [
        migrations.RunPython(seed, migrations.RunPython.noop),
        migrations.RunPython(roles, migrations.RunPython.noop),
    ]
