"""Archive imports asked for in the GUI or the API: queued jobs, kept with their outcome."""

from django.db import models
from django.utils.translation import gettext_lazy as _

from common.deferred_text import in_reader_language
from common.models import Job
from exchange.counts import count_lines


class ArchiveImport(Job):
    filename = models.CharField(
        max_length=255, help_text=_("The uploaded file's name."), verbose_name=_("filename")
    )
    # Absolute, so a worker started with another FTT_DATA_DIR still finds it;
    # emptied once the import ran (the file is deleted then).
    path = models.CharField(max_length=1000, blank=True, verbose_name=_("path"))
    verdict = models.CharField(max_length=200, blank=True, verbose_name=_("verdict"))
    verdict_said = models.JSONField(default=dict, blank=True, verbose_name=_("verdict (words)"))
    changes = models.IntegerField(null=True, blank=True, verbose_name=_("changes"))
    counts = models.JSONField(default=dict, blank=True, verbose_name=_("counts"))
    lines = models.JSONField(default=list, blank=True, verbose_name=_("lines"))

    class Meta(Job.Meta):
        verbose_name = _("archive import")
        verbose_name_plural = _("archive imports")
        pass

    @property
    def shown_lines(self) -> list[str]:
        """The counts table in the reader's language (``lines`` is in the worker's,
        FTT_LANGUAGE)."""
        return count_lines(self.counts) if self.counts else self.lines

    @property
    def shown_verdict(self) -> str:
        return in_reader_language(self.verdict, self.verdict_said)

    def __str__(self):
        return f"Import {self.pk} of {self.filename} ({self.status})"
