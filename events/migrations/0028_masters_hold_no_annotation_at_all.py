"""A master holds none of a reason's seven annotation fields, not only four of
them: initiator, severity and location type join the check
(docs/architecture.md, the rule table).  No path of FTT writes them on a master;
a row written around the services has them put back to what a new reason
starts with before the check is made, so the migration runs on any data."""

from django.db import migrations, models

# As the model states it at this migration (events.models.hierarchy.NO_ANNOTATION).
NO_ANNOTATION = dict.fromkeys(("obstacle", "lighting", "slope", "location_type"), "") | {
    "ito_reason": None,
    "initiator": "safety_driver",
    "severity": "not_applicable",
}


def clear_masters(apps, schema_editor):
    Segment = apps.get_model("events", "Segment")
    masters = Segment.objects.using(schema_editor.connection.alias).filter(parent__isnull=True)
    masters.exclude(**NO_ANNOTATION).update(**NO_ANNOTATION)


class Migration(migrations.Migration):
    dependencies = [("events", "0027_history_source")]

    operations = [
        migrations.RemoveConstraint(
            model_name="segment", name="segment_masters_have_no_annotation"
        ),
        migrations.RunPython(clear_masters, migrations.RunPython.noop),
        migrations.AddConstraint(
            model_name="segment",
            constraint=models.CheckConstraint(
                condition=models.Q(parent__isnull=False) | models.Q(**NO_ANNOTATION),
                name="segment_masters_have_no_annotation",
            ),
        ),
    ]
