"""The mode-source presets (rosbridge_app/collector/mode_presets.py).

manage.py ftt_mode_presets            each preset's name and what it reads
manage.py ftt_mode_presets autoware   its YAML, to paste as params.mode_sources
"""

from django.core.management.base import BaseCommand, CommandError
from django.utils.translation import gettext as _

from rosbridge_app.collector.mode_presets import PRESETS, preset


class Command(BaseCommand):
    help = _("List the mode-source presets, or print one to paste as params.mode_sources.")

    def add_arguments(self, parser):
        parser.add_argument(
            "name", nargs="?", help=_("The preset to print (without it: the list).")
        )

    def handle(self, *args, name=None, **options):
        if name is None:
            self.stdout.write(_("Presets for params.mode_sources (print one with its name):"))
            width = max(len(p.name) for p in PRESETS)
            for p in PRESETS:
                self.stdout.write(f"  {p.name.ljust(width)}  {p.summary}")
            return
        try:
            chosen = preset(name)
        except KeyError:
            raise CommandError(
                _("no preset %(name)s (there are: %(names)s)")
                % {"name": name, "names": ", ".join(p.name for p in PRESETS)}
            ) from None
        self.stdout.write(chosen.document, ending="")
