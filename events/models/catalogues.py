"""Seeded catalogues.  Their keys are primary keys so that data from several
installations refers to the same rows without any id mapping."""

from django.core.validators import RegexValidator
from django.db import models

from events.models.changes import tracked

rgb_validator = RegexValidator(r"^\d{1,3},\d{1,3},\d{1,3}$", "Colour must be 'R,G,B' (0-255 each).")


class Catalogue(models.Model):
    key = models.SlugField(primary_key=True, max_length=64)
    short_description = models.CharField(max_length=128)
    long_description = models.TextField(blank=True)

    class Meta:
        abstract = True
        ordering = ["short_description"]

    def __str__(self):
        return self.short_description


class Weather(Catalogue):
    icon = models.CharField(max_length=64, blank=True)

    class Meta(Catalogue.Meta):
        verbose_name_plural = "weather"


class SegmentType(Catalogue):
    ITO = "ito"
    AUTO = "auto"

    color = models.CharField(max_length=11, validators=[rgb_validator])

    class Meta(Catalogue.Meta):
        verbose_name = "segment type"


class ItoReason(Catalogue):
    UNASSIGNED = "unassigned"

    color = models.CharField(max_length=11, validators=[rgb_validator])
    counts_as_intervention = models.BooleanField(
        default=True,
        help_text="Counted as an intervention in reliability statistics (MCBI, MDBI).",
    )
    quick = models.BooleanField(
        default=False,
        help_text="Offered as a one-tap button in the cockpit (the others are in its list).",
    )
    history = tracked()

    class Meta(Catalogue.Meta):
        verbose_name = "ITO reason"
        verbose_name_plural = "ITO reasons"
