"""Archive imports asked for in the GUI or the API: queued jobs, kept with their outcome."""

from django.db import models

from common.models import Job


class ArchiveImport(Job):
    filename = models.CharField(max_length=255, help_text="The uploaded file's name.")
    # Absolute, so a worker started with another FTT_DATA_DIR still finds it;
    # emptied once the import ran (the file is deleted then).
    path = models.CharField(max_length=1000, blank=True)
    verdict = models.CharField(max_length=200, blank=True)
    changes = models.IntegerField(null=True, blank=True)
    counts = models.JSONField(default=dict, blank=True)
    lines = models.JSONField(default=list, blank=True)

    class Meta(Job.Meta):
        pass

    def __str__(self):
        return f"Import {self.pk} of {self.filename} ({self.status})"
