# The change feed now belongs to events (see events.0005). In the database only
# the foreign key to the collector goes: the feed keeps the collector's id.

from django.db import migrations, models


class Migration(migrations.Migration):
    dependencies = [
        ("rosbridge_app", "0002_announcement_kinds"),
        ("events", "0005_change_feed"),
    ]

    operations = [
        migrations.SeparateDatabaseAndState(
            database_operations=[
                migrations.AlterField(
                    model_name="announcement",
                    name="collector",
                    field=models.BigIntegerField(blank=True, null=True, db_column="collector_id"),
                ),
            ],
            state_operations=[migrations.DeleteModel(name="Announcement")],
        ),
    ]
