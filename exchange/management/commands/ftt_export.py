"""Write test events into an FTT archive: ``manage.py ftt_export OUT.zip [--event ID|UID ...]``."""

from django.core.management.base import BaseCommand, CommandError
from django.utils.dateparse import parse_datetime
from django.utils.translation import gettext as _

from exchange.export import ExportError, export_events, select_events


class Command(BaseCommand):
    help = _(
        "Export test events (default: all) with their shifts, legs, segments, notes, "
        "poses, maps and images into one archive file."
    )

    def add_arguments(self, parser):
        parser.add_argument("output", help=_("Archive file to write (.zip)."))
        parser.add_argument(
            "--event",
            action="append",
            dest="events",
            metavar="ID|UID",
            help=_("Test event to export, by id or uid; repeat for several. Default: all."),
        )
        parser.add_argument(
            "--since",
            help=_(
                "Only telemetry received at or after this ISO time (e.g. 2026-05-04T12:00Z); "
                "log entries and notes of the chosen events are always complete."
            ),
        )

    def handle(self, *args, output, events, since, **options):
        since_time = None
        if since:
            since_time = parse_datetime(since.replace("Z", "+00:00"))
            if since_time is None or since_time.tzinfo is None:
                raise CommandError(
                    _("--since %(since)s is not an ISO time with a UTC offset.")
                    % {"since": f"{since!r}"}
                )
        try:
            chosen = select_events(events, since_time)
            result = export_events(output, chosen, since=since_time)
        except ExportError as exc:
            raise CommandError(str(exc)) from None
        counts = ", ".join(f"{n} {table}" for table, n in result.counts.items() if n)
        self.stdout.write(
            _("Wrote %(path)s: %(events)s test event(s); %(counts)s; %(files)s file(s).")
            % {"path": result.path, "events": len(chosen), "counts": counts, "files": result.files}
        )
