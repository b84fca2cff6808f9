"""Seeded catalogues.  Their keys are primary keys so that data from several
installations refers to the same rows without any id mapping."""

from django.core.validators import RegexValidator
from django.db import models
from django.utils.translation import gettext_lazy as _

from events import seeds
from events.models.changes import tracked

rgb_validator = RegexValidator(r"^\d{1,3},\d{1,3},\d{1,3}$", "Colour must be 'R,G,B' (0-255 each).")


class Catalogue(models.Model):
    key = models.SlugField(primary_key=True, max_length=64, verbose_name=_("key"))
    short_description = models.CharField(max_length=128, verbose_name=_("short description"))
    long_description = models.TextField(blank=True, verbose_name=_("long description"))

    class Meta:
        abstract = True
        ordering = ["short_description"]

    def __str__(self):
        return self.shown_short

    @property
    def shown_short(self) -> str:
        """The short description in the reader's language if it is the seeded one."""
        return seeds.catalogue_text(self._meta.model_name, self.key, self.short_description)

    @property
    def shown_long(self) -> str:
        return seeds.catalogue_text(self._meta.model_name, self.key, self.long_description)


class Weather(Catalogue):
    icon = models.CharField(max_length=64, blank=True, verbose_name=_("icon"))

    class Meta(Catalogue.Meta):
        verbose_name = _("weather")
        verbose_name_plural = _("weather")


class SegmentType(Catalogue):
    ITO = "ito"
    AUTO = "auto"
    # Logged before the robot said its mode (rosbridge_app/collector/unknown_mode.py).
    UNKNOWN = "unknown"

    color = models.CharField(max_length=11, validators=[rgb_validator], verbose_name=_("color"))

    class Meta(Catalogue.Meta):
        verbose_name = _("segment type")
        verbose_name_plural = _("segment types")


class ItoReason(Catalogue):
    UNASSIGNED = "unassigned"

    color = models.CharField(max_length=11, validators=[rgb_validator], verbose_name=_("color"))
    counts_as_intervention = models.BooleanField(
        default=True,
        help_text=_("Counted as an intervention in reliability statistics (MCBI, MDBI)."),
        verbose_name=_("counts as intervention"),
    )
    quick = models.BooleanField(
        default=False,
        help_text=_("Offered as a one-tap button in the cockpit (the others are in its list)."),
        verbose_name=_("quick"),
    )
    history = tracked()

    class Meta(Catalogue.Meta):
        verbose_name = _("ITO reason")
        verbose_name_plural = _("ITO reasons")
