"""Create a robot account for the HTTP API, bound to its vehicles, and print its token.

    manage.py ftt_robot_account husky-robot --vehicle husky
    manage.py ftt_robot_account husky-robot --vehicle husky --new-token

Only the token goes to standard output, so that a script can keep it:
``TOKEN=$(manage.py ftt_robot_account husky-robot --vehicle husky)``.  Running it
again prints the same token and adds the vehicles named to those bound.
"""

from django.core.exceptions import ValidationError
from django.core.management.base import BaseCommand, CommandError
from django.utils.translation import gettext as _

from events.models import Vehicle
from events.services.robots import ensure_robot_account


class Command(BaseCommand):
    help = _("Create (or extend) a robot account bound to vehicles and print its API token.")

    def add_arguments(self, parser):
        parser.add_argument("name", help=_("User name of the robot's account, e.g. husky-robot."))
        parser.add_argument(
            "--vehicle",
            action="append",
            required=True,
            metavar="KEY",
            help=_("Key of a vehicle the robot logs for; repeat for several."),
        )
        parser.add_argument(
            "--new-token",
            action="store_true",
            help=_("Replace the account's token (the old one stops working)."),
        )

    def handle(self, *args, name, vehicle, new_token, **options):
        found = {v.key: v for v in Vehicle.objects.filter(key__in=vehicle)}
        missing = [key for key in vehicle if key not in found]
        if missing:
            known = ", ".join(Vehicle.objects.values_list("key", flat=True)) or _("none yet")
            raise CommandError(
                _("No vehicle with key %(keys)s (known: %(known)s).")
                % {"keys": ", ".join(missing), "known": known}
            )
        try:
            login = ensure_robot_account(name, list(found.values()), new_token=new_token)
        except ValidationError as exc:
            raise CommandError(" ".join(exc.messages)) from exc
        bound = ", ".join(login.account.vehicles.values_list("key", flat=True))
        line = (
            _("Created robot account '%(name)s', bound to: %(bound)s.")
            if login.created
            else _("Updated robot account '%(name)s', bound to: %(bound)s.")
        )
        self.stderr.write(line % {"name": name, "bound": bound})
        self.stdout.write(login.token)
