"""A test event's plan: test cases with their pass criteria, and the judgements a
person records for criteria that figures cannot decide."""

from django.conf import settings
from django.contrib.gis.db import models
from django.db.models import Q

from events.models.catalogues import ItoReason
from events.models.hierarchy import Leg, TestEvent


class TestCase(models.Model):
    """One planned trial, e.g. "three autonomous runs of the gravel loop"."""

    __test__ = False  # not a pytest class

    test_event = models.ForeignKey(TestEvent, on_delete=models.CASCADE, related_name="test_cases")
    key = models.SlugField(max_length=50, help_text="Short name, e.g. gravel-loop.")
    title = models.CharField(max_length=200)
    description = models.TextField(blank=True)
    area = models.MultiPolygonField(
        srid=4326, null=True, blank=True, help_text="Where the case is driven (optional)."
    )
    route = models.LineStringField(
        srid=4326, null=True, blank=True, help_text="The planned route (optional)."
    )
    planned_runs = models.PositiveIntegerField(
        default=1, help_text="How many legs the plan asks for."
    )

    class Meta:
        ordering = ["test_event", "key"]
        constraints = [
            models.UniqueConstraint(fields=["test_event", "key"], name="test_case_key_unique"),
            models.CheckConstraint(condition=Q(planned_runs__gte=1), name="test_case_runs_min"),
        ]

    def __str__(self):
        return f"{self.key}: {self.title}"


class Criterion(models.Model):
    """A pass criterion of a test case, from a small typed set."""

    class Kind(models.TextChoices):
        DISTANCE_WITHOUT_INTERVENTION = (
            "distance_without_intervention",
            ("distance without intervention ≥ value (m)"),
        )
        INTERVENTIONS_PER_KM = "interventions_per_km", "interventions per km ≤ value"
        RUNS_COMPLETED = "runs_completed", "runs completed ≥ value"
        AUTO_TIME_SHARE = "auto_time_share", "time in AUTO ≥ value (%)"
        FORBIDDEN_REASONS = "forbidden_reasons", "none of the reasons occurs"
        JUDGED = "judged", "judged by a person (text)"

    # Kinds measured per leg; the others only make sense over the whole case.
    PER_LEG = (
        Kind.DISTANCE_WITHOUT_INTERVENTION,
        Kind.INTERVENTIONS_PER_KM,
        Kind.AUTO_TIME_SHARE,
        Kind.FORBIDDEN_REASONS,
    )

    test_case = models.ForeignKey(TestCase, on_delete=models.CASCADE, related_name="criteria")
    kind = models.CharField(max_length=40, choices=Kind.choices)
    value = models.FloatField(null=True, blank=True, help_text="The threshold of the kind.")
    reasons = models.ManyToManyField(
        ItoReason, blank=True, related_name="+", help_text="For 'none of the reasons occurs'."
    )
    text = models.TextField(blank=True, help_text="What a person judges, for 'judged'.")

    class Meta:
        ordering = ["test_case", "id"]
        verbose_name_plural = "criteria"

    def __str__(self):
        if self.kind == self.Kind.JUDGED:
            return self.text[:80]
        if self.kind == self.Kind.FORBIDDEN_REASONS:
            return self.get_kind_display()
        return self.get_kind_display().replace("value", f"{self.value:g}")


class Judgement(models.Model):
    """A person's verdict on a judged criterion, for the whole case or one leg."""

    criterion = models.ForeignKey(Criterion, on_delete=models.CASCADE, related_name="judgements")
    leg = models.ForeignKey(
        Leg, on_delete=models.CASCADE, null=True, blank=True, related_name="judgements"
    )
    passed = models.BooleanField()
    note = models.TextField(blank=True)
    by = models.ForeignKey(
        settings.AUTH_USER_MODEL, on_delete=models.SET_NULL, null=True, related_name="+"
    )
    at = models.DateTimeField(auto_now=True)

    class Meta:
        constraints = [
            models.UniqueConstraint(fields=["criterion", "leg"], name="one_judgement_per_leg"),
            models.UniqueConstraint(
                fields=["criterion"],
                condition=Q(leg__isnull=True),
                name="one_judgement_per_case",
            ),
        ]
