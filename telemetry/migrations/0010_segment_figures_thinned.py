from django.db import migrations, models


class Migration(migrations.Migration):
    dependencies = [
        ("telemetry", "0009_image_history"),
    ]

    operations = [
        migrations.AddField(
            model_name="segmentfigures",
            name="thinned",
            field=models.BooleanField(default=False, db_default=False),
        ),
    ]
