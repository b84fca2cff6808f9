"""The change history of every row that moves a figure or a record.

django-simple-history keeps one historical row per save or delete (values
after the change; the one before it is the previous entry).  Each entry adds
through what the change came (``history_channel``); who made it is
simple-history's ``history_user`` (an account, or the robot account whose
token wrote it), the reason its ``history_change_reason``.
``events.history`` fills both from the request or the caller's context.
Rows brought by an archive name their author in ``history_author`` instead
(accounts are not carried between installations) and the installation that
recorded them in ``history_source`` (exchange.history_records).
Poses are not tracked: they are only ever added, never changed, and a
history row per pose would double the cost of the busiest write.
"""

from django.db import models
from simple_history.models import HistoricalRecords

CHANNELS = (
    ("gui", "GUI"),
    ("api", "API"),
    ("legacy", "original robots' API"),
    ("admin", "admin"),
    ("collector", "collector"),
    ("import", "import"),
    ("system", "system"),
)


class ChangeOrigin(models.Model):
    history_channel = models.CharField(max_length=16, choices=CHANNELS, default="system")
    # The account's name where the change was made, for rows another
    # installation recorded; empty for changes made here (history_user).
    history_author = models.CharField(max_length=150, blank=True, default="")
    # The installation an imported entry was recorded on (the archive's
    # manifest); empty for changes made here.  An imported entry is that
    # installation's record: never an amendment here, its author only a name.
    history_source = models.CharField(max_length=150, blank=True, default="")

    class Meta:
        abstract = True


class IndexedByRow(HistoricalRecords):
    """History rows indexed only by the row they belong to (``id``) and by date:
    the only two ways they are looked up (``events.selectors.history``).  The
    copied columns' own indexes (foreign keys, uid) would each be written with
    every history row and never read.  Spatial indexes stay: SpatiaLite cannot
    drop one by migration."""

    def copy_fields(self, model):
        fields = super().copy_fields(model)
        for name, field in fields.items():
            if name != model._meta.pk.attname:
                field.db_index = False
        return fields


def tracked(**options) -> HistoricalRecords:
    """The history of one model; the user link never blocks deleting an account."""
    return IndexedByRow(
        bases=[ChangeOrigin],
        user_related_name="+",
        history_change_reason_field=models.TextField(null=True),
        **options,
    )
