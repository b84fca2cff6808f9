from django.db import migrations, models


class Migration(migrations.Migration):
    dependencies = [
        ("rosbridge_app", "0005_collector_hearing"),
    ]

    operations = [
        migrations.AddField(
            model_name="collector",
            name="stored",
            field=models.PositiveBigIntegerField(
                default=0,
                help_text="Records written to the database since the collector started.",
            ),
        ),
    ]
