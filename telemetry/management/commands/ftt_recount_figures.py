"""Measure every master segment's figures from its poses again and say where the
figures stored at write time differed (there should never be a difference).

    manage.py ftt_recount_figures            # report only; exit status 1 on a difference
    manage.py ftt_recount_figures --fix      # also set the stored figures right
    manage.py ftt_recount_figures --event 7  # one test event
"""

from django.core.management.base import BaseCommand, CommandError
from django.db import transaction
from django.utils.translation import gettext as _

from events.models import Segment
from telemetry.services.segment_figures import recount_figures

# Masters measured per transaction: a few thousand poses each at campaign scale.
CHUNK = 200


class Command(BaseCommand):
    help = _("Measure the per-segment figures from the poses and report where they differed.")

    def add_arguments(self, parser):
        parser.add_argument("--fix", action="store_true", help=_("Set differing figures right."))
        parser.add_argument("--event", type=int, help=_("Only the masters of this test event."))

    def handle(self, *args, fix, event, **options):
        masters = Segment.objects.masters()
        if event is not None:
            masters = masters.filter(leg__shift__test_event=event)
        # Thinned by the retention policy: the stored figures are from every pose,
        # which are no longer there to measure.
        thinned = masters.filter(thinning__isnull=False).count()
        masters = masters.filter(thinning__isnull=True)
        ids = list(masters.order_by("pk").values_list("pk", flat=True))
        differing = 0
        for begin in range(0, len(ids), CHUNK):
            with transaction.atomic():
                found = recount_figures(ids[begin : begin + CHUNK], fix=fix)
            for (segment, mode), diffs in sorted(found.items()):
                differing += 1
                self.stdout.write(
                    _("segment %(segment)s (%(mode)s): %(diffs)s")
                    % {"segment": segment, "mode": mode, "diffs": "; ".join(diffs)}
                )
        self.stdout.write(
            _("%(count)s masters measured, %(differing)s figures differed%(fixed)s.")
            % {
                "count": len(ids),
                "differing": differing,
                "fixed": _(" (set right)") if fix and differing else "",
            }
        )
        if thinned:
            self.stdout.write(
                _("%(count)s masters with thinned poses left out (their stored figures stand).")
                % {"count": thinned}
            )
        if differing and not fix:
            raise CommandError(_("The stored figures differ from the poses."))
