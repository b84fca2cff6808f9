"""Rows the test administrator maintains in Django admin."""

from django.conf import settings
from django.db import models

from events.models.changes import tracked


class Personnel(models.Model):
    name = models.CharField(max_length=200)
    institution = models.CharField(max_length=200, blank=True)
    user = models.OneToOneField(
        settings.AUTH_USER_MODEL,
        null=True,
        blank=True,
        on_delete=models.SET_NULL,
        related_name="personnel",
        help_text="Login account of this person; notes they write are attributed to them.",
    )
    history = tracked(excluded_fields=["user"])

    class Meta:
        ordering = ["name"]
        verbose_name_plural = "personnel"

    def __str__(self):
        return f"{self.name} ({self.institution})" if self.institution else self.name


class Performer(models.Model):
    institution = models.CharField(max_length=200, unique=True)

    class Meta:
        ordering = ["institution"]

    def __str__(self):
        return self.institution


class KeyedConfiguration(models.Model):
    key = models.SlugField(max_length=64, unique=True)
    short_description = models.CharField(max_length=200)
    long_description = models.TextField(blank=True)

    class Meta:
        abstract = True
        ordering = ["key"]

    def __str__(self):
        return self.short_description or self.key


class Vehicle(KeyedConfiguration):
    key = models.SlugField(
        max_length=64,
        unique=True,
        help_text="Name the collector is started with: ftt_collect --vehicle <key>.",
    )
    institution = models.CharField(max_length=200, blank=True)
    configuration = models.TextField(blank=True)
    history = tracked()

    class Meta(KeyedConfiguration.Meta):
        pass


class PoseSource(KeyedConfiguration):
    key = models.SlugField(
        max_length=64,
        unique=True,
        help_text="Stable name of this source; archives refer to it by this key.",
    )

    class Meta(KeyedConfiguration.Meta):
        pass
