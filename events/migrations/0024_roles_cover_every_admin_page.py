"""Give the role groups the rights of models made after events.0007: test
cases, criteria, judgements, finalising, basemaps.  A fresh install made the
groups before those models existed, so its administrators were refused them."""

from django.db import migrations

from events import seeds


def roles(apps, schema_editor):
    seeds.create_roles(apps)


class Migration(migrations.Migration):
    dependencies = [
        ("events", "0023_vehicle_vin"),
        ("telemetry", "0015_figures_keep_a_uid_sum"),
        ("basemaps", "0004_translated_labels"),
        ("auth", "0012_alter_user_first_name_max_length"),
    ]

    operations = [migrations.RunPython(roles, migrations.RunPython.noop)]
