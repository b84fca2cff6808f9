from django.db import migrations, models

from events.seeds import mark_quick_reasons


def forwards(apps, schema_editor):
    mark_quick_reasons(apps)


class Migration(migrations.Migration):
    dependencies = [
        ("events", "0007_robot_accounts"),
    ]

    operations = [
        migrations.AddField(
            model_name="itoreason",
            name="quick",
            field=models.BooleanField(
                default=False,
                help_text="Offered as a one-tap button in the cockpit (the others are in its list).",
            ),
        ),
        migrations.RunPython(forwards, migrations.RunPython.noop),
    ]
