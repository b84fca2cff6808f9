"""Daily upkeep of the stored poses (``manage.py ftt_worker`` runs it once a day):

    manage.py ftt_pose_storage                 # partitions, then the retention policy
    manage.py ftt_pose_storage --retention-months 24   # another age than the setting

PostgreSQL: the coming months' pose partitions are made and months found in
the default partition moved out (telemetry.services.pose_partitions).  Then,
when FTT_POSE_RETENTION_MONTHS (or the option) is set, the poses of older
shifts are thinned to what the report draws (reports.services.pose_retention).
"""

from django.core.management.base import BaseCommand
from django.utils.translation import gettext as _

from reports.services.pose_retention import thin_old_poses
from telemetry.services.pose_partitions import ensure_partitions


class Command(BaseCommand):
    help = _("Make the coming months' pose partitions and apply the retention policy.")

    def add_arguments(self, parser):
        parser.add_argument(
            "--retention-months",
            type=int,
            help=_("Thin poses of shifts older than this many months (default: the setting)."),
        )

    def handle(self, *args, retention_months, **options):
        made = ensure_partitions()
        self.stdout.write(
            _("%(count)s partitions made%(names)s.")
            % {"count": len(made), "names": (": " + ", ".join(made)) if made else ""}
        )
        deleted = thin_old_poses(retention_months)
        self.stdout.write(_("%(count)s poses thinned out.") % {"count": deleted})
