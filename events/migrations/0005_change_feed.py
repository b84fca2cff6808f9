# The change feed moves from rosbridge_app to events (the bottom layer); the
# table keeps its name, so only Django's model state changes here.

import django.db.models.deletion
import django.utils.timezone
from django.db import migrations, models


class Migration(migrations.Migration):
    dependencies = [
        ("events", "0004_change_stamps"),
        ("rosbridge_app", "0002_announcement_kinds"),
    ]

    operations = [
        migrations.SeparateDatabaseAndState(
            state_operations=[
                migrations.CreateModel(
                    name="Announcement",
                    fields=[
                        (
                            "id",
                            models.BigAutoField(
                                auto_created=True, primary_key=True, serialize=False, verbose_name="ID"
                            ),
                        ),
                        (
                            "kind",
                            models.CharField(
                                choices=[
                                    ("collector", "collector status"),
                                    ("log", "test event, shift or leg"),
                                    ("deleted", "row deleted"),
                                    ("note", "note"),
                                    ("segment", "segment opened or closed"),
                                    ("poses", "GPS poses"),
                                    ("local_poses", "local poses"),
                                    ("image", "image"),
                                    ("map", "map"),
                                    ("command", "command result"),
                                ],
                                max_length=16,
                            ),
                        ),
                        (
                            "created",
                            models.DateTimeField(db_index=True, default=django.utils.timezone.now),
                        ),
                        ("collector_id", models.BigIntegerField(blank=True, null=True)),
                        ("payload", models.JSONField(blank=True, default=dict)),
                        (
                            "leg",
                            models.ForeignKey(
                                blank=True,
                                null=True,
                                on_delete=django.db.models.deletion.CASCADE,
                                related_name="+",
                                to="events.leg",
                            ),
                        ),
                    ],
                    options={"db_table": "rosbridge_app_announcement", "ordering": ["id"]},
                ),
            ],
            database_operations=[],
        ),
    ]
