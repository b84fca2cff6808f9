"""A test event's plan: test cases with their pass criteria, and the judgements a
person records for criteria that figures cannot decide."""

import math

from django.conf import settings
from django.contrib.gis.db import models
from django.core.exceptions import ValidationError
from django.db.models import Q
from django.utils.translation import gettext as _
from django.utils.translation import gettext_lazy

from events.models.catalogues import ItoReason
from events.models.hierarchy import Leg, TestEvent


class TestCase(models.Model):
    """One planned trial, e.g. "three autonomous runs of the gravel loop"."""

    __test__ = False  # not a pytest class

    test_event = models.ForeignKey(
        TestEvent,
        on_delete=models.CASCADE,
        related_name="test_cases",
        verbose_name=gettext_lazy("test event"),
    )
    key = models.SlugField(
        gettext_lazy("key"), max_length=50, help_text=gettext_lazy("Short name, e.g. gravel-loop.")
    )
    title = models.CharField(gettext_lazy("title"), max_length=200)
    description = models.TextField(gettext_lazy("description"), blank=True)
    area = models.MultiPolygonField(
        gettext_lazy("area"),
        srid=4326,
        null=True,
        blank=True,
        help_text=gettext_lazy("Where the case is driven (optional)."),
    )
    route = models.LineStringField(
        gettext_lazy("route"),
        srid=4326,
        null=True,
        blank=True,
        help_text=gettext_lazy("The planned route (optional)."),
    )
    planned_runs = models.PositiveIntegerField(
        gettext_lazy("planned runs"),
        default=1,
        help_text=gettext_lazy("How many legs the plan asks for."),
    )

    class Meta:
        verbose_name = gettext_lazy("test case")
        verbose_name_plural = gettext_lazy("test cases")
        ordering = ["test_event", "key"]
        constraints = [
            models.UniqueConstraint(fields=["test_event", "key"], name="test_case_key_unique"),
            models.CheckConstraint(condition=Q(planned_runs__gte=1), name="test_case_runs_min"),
        ]

    def __str__(self):
        return f"{self.key}: {self.title}"

    def clean(self):
        errors = {}
        for name in ("area", "route"):
            problem = _geometry_problem(getattr(self, name))
            if problem:
                errors[name] = [problem]
        if errors:
            raise ValidationError(errors)


def _geometry_problem(geometry) -> str | None:
    """Why an area or route cannot be on the globe (or be tested against), or None."""
    if geometry is None:
        return None
    extent = geometry.extent
    if not all(math.isfinite(v) for v in extent):
        return _("The coordinates must be finite numbers.")
    west, south, east, north = extent
    if west < -180 or east > 180 or south < -90 or north > 90:
        return _("Longitudes must lie within ±180° and latitudes within ±90°.")
    if not geometry.valid:
        return _("This is not a valid shape (%(reason)s).") % {"reason": geometry.valid_reason}
    return None


class Criterion(models.Model):
    """A pass criterion of a test case, from a small typed set."""

    class Kind(models.TextChoices):
        DISTANCE_WITHOUT_INTERVENTION = (
            "distance_without_intervention",
            gettext_lazy("distance without intervention ≥ value (m)"),
        )
        INTERVENTIONS_PER_KM = (
            "interventions_per_km",
            gettext_lazy("interventions per km ≤ value"),
        )
        RUNS_COMPLETED = "runs_completed", gettext_lazy("runs completed ≥ value")
        AUTO_TIME_SHARE = "auto_time_share", gettext_lazy("time in AUTO ≥ value (%)")
        FORBIDDEN_REASONS = "forbidden_reasons", gettext_lazy("none of the reasons occurs")
        JUDGED = "judged", gettext_lazy("judged by a person (text)")

    # Kinds measured per leg; the others only make sense over the whole case.
    PER_LEG = (
        Kind.DISTANCE_WITHOUT_INTERVENTION,
        Kind.INTERVENTIONS_PER_KM,
        Kind.AUTO_TIME_SHARE,
        Kind.FORBIDDEN_REASONS,
    )

    test_case = models.ForeignKey(
        TestCase,
        on_delete=models.CASCADE,
        related_name="criteria",
        verbose_name=gettext_lazy("test case"),
    )
    kind = models.CharField(gettext_lazy("kind"), max_length=40, choices=Kind.choices)
    value = models.FloatField(
        gettext_lazy("value"),
        null=True,
        blank=True,
        help_text=gettext_lazy("The threshold of the kind."),
    )
    reasons = models.ManyToManyField(
        ItoReason,
        blank=True,
        related_name="+",
        verbose_name=gettext_lazy("reasons"),
        help_text=gettext_lazy("For 'none of the reasons occurs'."),
    )
    text = models.TextField(
        gettext_lazy("text"),
        blank=True,
        help_text=gettext_lazy("What a person judges, for 'judged'."),
    )

    class Meta:
        ordering = ["test_case", "id"]
        verbose_name = gettext_lazy("criterion")
        verbose_name_plural = gettext_lazy("criteria")

    def __str__(self):
        if self.kind == self.Kind.JUDGED:
            return self.text[:80]
        if self.kind == self.Kind.FORBIDDEN_REASONS or self.value is None:
            return str(self.get_kind_display())
        # The label names the threshold "value" (in the active language).
        return str(self.get_kind_display()).replace(_("value"), f"{self.value:g}")

    @property
    def lacks_threshold(self) -> bool:
        """A measured kind stored without its value (refused since, but an older
        installation could keep one): nothing can be compared with it."""
        return self.kind in THRESHOLDS and self.value is None

    def clean(self):
        errors = {}
        value = self.value
        if self.kind in THRESHOLDS:
            low, high, whole = THRESHOLDS[self.kind]
            if value is None:
                errors["value"] = [_("This kind of criterion needs a value.")]
            elif not isinstance(value, int | float):
                pass  # no number: clean_fields says so
            elif not math.isfinite(value) or value < low:
                errors["value"] = [_("The value must be at least %(low)s.") % {"low": low}]
            elif high is not None and value > high:
                errors["value"] = [
                    _("The value must lie between %(low)s and %(high)s.")
                    % {"low": low, "high": high}
                ]
            elif whole and value != int(value):
                errors["value"] = [_("The value must be a whole number.")]
        if self.kind == self.Kind.JUDGED and not self.text.strip():
            errors["text"] = [_("Say what a person judges.")]
        if errors:
            raise ValidationError(errors)

    @classmethod
    def check_reasons(cls, kind: str, reasons) -> None:
        """The reasons a criterion names, checked apart from :meth:`clean`: they are
        set after the row is saved."""
        if kind == cls.Kind.FORBIDDEN_REASONS and not reasons:
            raise ValidationError({"reasons": [_("Choose at least one reason.")]})


# The measured kinds: least and greatest value, and whether it counts whole runs.
THRESHOLDS = {
    Criterion.Kind.DISTANCE_WITHOUT_INTERVENTION: (0, None, False),
    Criterion.Kind.INTERVENTIONS_PER_KM: (0, None, False),
    Criterion.Kind.RUNS_COMPLETED: (1, None, True),
    Criterion.Kind.AUTO_TIME_SHARE: (0, 100, False),
}


class Judgement(models.Model):
    """A person's verdict on a judged criterion, for the whole case or one leg."""

    criterion = models.ForeignKey(
        Criterion,
        on_delete=models.CASCADE,
        related_name="judgements",
        verbose_name=gettext_lazy("criterion"),
    )
    leg = models.ForeignKey(
        Leg,
        on_delete=models.CASCADE,
        null=True,
        blank=True,
        related_name="judgements",
        verbose_name=gettext_lazy("leg"),
    )
    passed = models.BooleanField(gettext_lazy("passed"))
    note = models.TextField(gettext_lazy("note"), blank=True)
    by = models.ForeignKey(
        settings.AUTH_USER_MODEL,
        on_delete=models.SET_NULL,
        null=True,
        related_name="+",
        verbose_name=gettext_lazy("judged by"),
    )
    at = models.DateTimeField(gettext_lazy("judged at"), auto_now=True)

    class Meta:
        verbose_name = gettext_lazy("judgement")
        verbose_name_plural = gettext_lazy("judgements")
        constraints = [
            models.UniqueConstraint(fields=["criterion", "leg"], name="one_judgement_per_leg"),
            models.UniqueConstraint(
                fields=["criterion"],
                condition=Q(leg__isnull=True),
                name="one_judgement_per_case",
            ),
        ]
