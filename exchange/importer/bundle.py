"""Importing a whole archive: every step in one transaction, announced in the change
feed, and every failure turned into :class:`ImportRefused` with nothing changed."""

from django.core.exceptions import ValidationError
from django.db import DatabaseError, IntegrityError, transaction
from django.utils.translation import gettext

from events import feed
from events.history import authored
from events.models import Segment
from events.services.finality import finalisations_arriving
from exchange import records as rec
from exchange.archive import ArchiveError
from exchange.importer import configuration, history, logbook, plans, telemetry
from exchange.importer.plan import ImportRefused, MalformedRecord, Plan, describe
from exchange.importer.session import ImportSession

# In this order: a row's parents and configuration come before it.
STEPS = (
    configuration.import_catalogues,
    configuration.import_configuration,
    logbook.import_test_events,
    logbook.link_basemaps,
    plans.import_test_cases,
    logbook.import_shifts,
    logbook.import_legs,
    plans.import_judgements,
    logbook.import_segments,
    logbook.import_notes,
    telemetry.import_poses,
    telemetry.import_local_poses,
    telemetry.import_maps,
    telemetry.import_images,
    telemetry.import_recordings,
    history.import_history,
    logbook.refuse_open_under_closed,
    logbook.refuse_changes_to_final,
)


def announce_changes(session: ImportSession):
    """Open browsers see an import like any other change (same transaction)."""
    for row in session.changed:
        feed.announce_row(row)
    masters = Segment.objects.in_bulk({segment for _, segment in session.track_points})
    for (table, segment), count in session.track_points.items():
        kind = "poses" if table == "poses" else "local_poses"
        # No points inline: the page re-reads the track.
        feed.announce(kind, masters[segment], segment=segment, mode=None, count=count)


def import_bundle(bundle, *, dry_run: bool = False, by=None) -> Plan:
    """Apply a verified archive (or any object with ``records(table)`` and
    ``read_file(name)``).  Raises :class:`ImportRefused`; then nothing changed.

    The import's own changes are ``by``'s (the administrator who imports), on
    channel ``import``, with the import as their reason: on a final event that
    is an amendment (events.services.finality), which only an administrator
    may make."""
    session = ImportSession(bundle, dry_run)
    origin = authored("import", user=by, reason=gettext("archive import"))
    try:
        with origin, transaction.atomic(), finalisations_arriving() as arriving:
            session.arriving = arriving
            for step in STEPS:
                step(session)
            announce_changes(session)
            if dry_run:
                transaction.set_rollback(True)
    except ImportRefused as exc:
        session.discard_files()
        raise type(exc)(f"{exc} Nothing was imported.") from None
    except ValidationError as exc:
        session.discard_files()
        raise ImportRefused(
            gettext("%(where)s: %(reason)s. Nothing was imported.")
            % {"where": session.where, "reason": describe(exc)}
        ) from None
    except (
        ArchiveError,
        rec.RecordError,
        LookupError,
        AttributeError,
        TypeError,
        ValueError,
        OverflowError,
    ) as exc:
        session.discard_files()
        what = (
            gettext("missing field %(field)s") % {"field": exc}
            if isinstance(exc, KeyError)
            else str(exc)
        )
        raise MalformedRecord(
            gettext("%(where)s: malformed record (%(what)s). Nothing was imported.")
            % {"where": session.where, "what": what}
        ) from None
    except (IntegrityError, DatabaseError) as exc:
        session.discard_files()
        raise ImportRefused(
            gettext("%(where)s: the database refused it (%(reason)s). Nothing was imported.")
            % {"where": session.where, "reason": str(exc).strip()}
        ) from None
    except BaseException:
        session.discard_files()
        raise
    return session.plan
