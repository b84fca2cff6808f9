"""Rows the test administrator maintains in Django admin."""

from django.conf import settings
from django.db import models
from django.utils.translation import gettext_lazy as _

from events.models.changes import tracked


class Personnel(models.Model):
    name = models.CharField(max_length=200, verbose_name=_("name"))
    institution = models.CharField(max_length=200, blank=True, verbose_name=_("institution"))
    user = models.OneToOneField(
        settings.AUTH_USER_MODEL,
        null=True,
        blank=True,
        on_delete=models.SET_NULL,
        related_name="personnel",
        help_text=_("Login account of this person; notes they write are attributed to them."),
        verbose_name=_("user"),
    )
    history = tracked(excluded_fields=["user"])

    class Meta:
        verbose_name = _("person")
        verbose_name_plural = _("personnel")
        ordering = ["name"]

    def __str__(self):
        return f"{self.name} ({self.institution})" if self.institution else self.name


class Performer(models.Model):
    institution = models.CharField(max_length=200, unique=True, verbose_name=_("institution"))

    class Meta:
        verbose_name = _("performer")
        verbose_name_plural = _("performers")
        ordering = ["institution"]

    def __str__(self):
        return self.institution


class KeyedConfiguration(models.Model):
    key = models.SlugField(max_length=64, unique=True, verbose_name=_("key"))
    short_description = models.CharField(max_length=200, verbose_name=_("short description"))
    long_description = models.TextField(blank=True, verbose_name=_("long description"))

    class Meta:
        abstract = True
        ordering = ["key"]

    def __str__(self):
        return self.short_description or self.key


class Vehicle(KeyedConfiguration):
    key = models.SlugField(
        max_length=64,
        unique=True,
        help_text=_("Name the collector is started with: ftt_collect --vehicle <key>."),
        verbose_name=_("key"),
    )
    institution = models.CharField(max_length=200, blank=True, verbose_name=_("institution"))
    configuration = models.TextField(blank=True, verbose_name=_("configuration"))
    vin = models.CharField(
        max_length=64,
        blank=True,
        verbose_name=_("vehicle identification number"),
        help_text=_("VIN or serial number for the disengagement report; empty: its key."),
    )
    history = tracked()

    class Meta(KeyedConfiguration.Meta):
        verbose_name = _("vehicle")
        verbose_name_plural = _("vehicles")
        pass


class PoseSource(KeyedConfiguration):
    key = models.SlugField(
        max_length=64,
        unique=True,
        help_text=_("Stable name of this source; archives refer to it by this key."),
        verbose_name=_("key"),
    )

    class Meta(KeyedConfiguration.Meta):
        verbose_name = _("pose source")
        verbose_name_plural = _("pose sources")
        pass
