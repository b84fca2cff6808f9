import django.db.models.deletion
import django.utils.timezone
from django.db import migrations, models


class Migration(migrations.Migration):
    dependencies = [
        ("events", "0017_change_history_finalising_and_regulator_fields"),
        ("telemetry", "0011_history_indexed_by_row_only"),
    ]

    operations = [
        migrations.CreateModel(
            name="ThinnedSegment",
            fields=[
                (
                    "id",
                    models.BigAutoField(
                        auto_created=True, primary_key=True, serialize=False, verbose_name="ID"
                    ),
                ),
                ("thinned", models.DateTimeField(default=django.utils.timezone.now)),
                (
                    "segment",
                    models.OneToOneField(
                        on_delete=django.db.models.deletion.CASCADE,
                        related_name="thinning",
                        to="events.segment",
                    ),
                ),
            ],
        ),
    ]
