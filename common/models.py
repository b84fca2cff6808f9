"""The tables of the shared plumbing: which job workers are alive, and each
account's preferences."""

from django.conf import settings
from django.db import models
from django.utils.translation import gettext_lazy as _

from common.deferred_text import in_reader_language


class JobWorker(models.Model):
    """A running ``manage.py ftt_worker``; it renews ``beat`` while it lives.

    django-tasks leaves a task "running" forever when its worker is killed;
    this row is how another worker tells a dead worker from a busy one.
    """

    worker_id = models.CharField(max_length=64, primary_key=True, verbose_name=_("worker id"))
    host = models.CharField(max_length=255, verbose_name=_("host"))
    pid = models.IntegerField(verbose_name=_("pid"))
    started = models.DateTimeField(verbose_name=_("started"))
    beat = models.DateTimeField(verbose_name=_("beat"))

    def __str__(self):
        return f"job worker {self.worker_id}"


class Job(models.Model):
    """What every row that a background job works on shows: its state and outcome."""

    class Status(models.TextChoices):
        QUEUED = "queued", _("queued")
        RUNNING = "running", _("running")
        DONE = "done", _("done")
        FAILED = "failed", _("failed")

    status = models.CharField(
        max_length=10, choices=Status.choices, default=Status.QUEUED, verbose_name=_("status")
    )
    message = models.CharField(
        max_length=200, blank=True, help_text=_("The step running now."), verbose_name=_("message")
    )
    error = models.TextField(blank=True, verbose_name=_("error"))
    # The message and error as text and values (common.deferred_text), read in the
    # reader's language.
    message_said = models.JSONField(default=dict, blank=True, verbose_name=_("message (words)"))
    error_said = models.JSONField(default=dict, blank=True, verbose_name=_("error (words)"))
    requested_by = models.ForeignKey(
        settings.AUTH_USER_MODEL,
        null=True,
        blank=True,
        on_delete=models.SET_NULL,
        related_name="+",
        verbose_name=_("requested by"),
    )
    created = models.DateTimeField(auto_now_add=True, verbose_name=_("created"))
    updated = models.DateTimeField(auto_now=True, verbose_name=_("updated"))
    finished = models.DateTimeField(null=True, blank=True, verbose_name=_("finished"))

    class Meta:
        abstract = True
        ordering = ["-created", "-id"]

    @property
    def shown_message(self) -> str:
        return in_reader_language(self.message, self.message_said)

    @property
    def shown_error(self) -> str:
        return in_reader_language(self.error, self.error_said)

    @property
    def is_finished(self) -> bool:
        return self.status in (self.Status.DONE, self.Status.FAILED)


class AccountPreference(models.Model):
    """What an account chose for itself; read by ftt_site.inbound.language."""

    user = models.OneToOneField(
        settings.AUTH_USER_MODEL,
        on_delete=models.CASCADE,
        related_name="preference",
        verbose_name=_("account"),
    )
    language = models.CharField(
        max_length=8,
        choices=settings.LANGUAGES,
        blank=True,
        help_text=_("Empty: the language the browser asks for."),
        verbose_name=_("language"),
    )

    class Meta:
        verbose_name = _("account preference")
        verbose_name_plural = _("account preferences")

    def __str__(self):
        return f"{self.user}: {self.language or '-'}"


class DirectoryAccount(models.Model):
    """Marks an account that a directory sign-in made (common.directory).

    Only these accounts are ever signed in, or changed, by the directory; a
    local account of the same name keeps the name for itself.
    """

    user = models.OneToOneField(
        settings.AUTH_USER_MODEL,
        on_delete=models.CASCADE,
        related_name="directory_account",
        verbose_name=_("account"),
    )
    created = models.DateTimeField(auto_now_add=True, verbose_name=_("created"))
    # When the directory was last asked for this account's role (at sign-in, at
    # use, on the worker's schedule), answered or not: the next ask waits
    # FTT_LDAP_RECHECK_SECONDS from here.
    role_checked = models.DateTimeField(null=True, blank=True, verbose_name=_("role checked"))

    class Meta:
        verbose_name = _("directory account")
        verbose_name_plural = _("directory accounts")

    def __str__(self):
        return str(self.user)
