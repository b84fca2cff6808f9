"""manage.py ftt_basemap: prepare and register offline basemaps.

    manage.py ftt_basemap fetch --bbox 7.10,50.60,7.14,50.62 --zooms 14-19 \\
        --from "https://tile.example.org/{z}/{x}/{y}.png" field.pmtiles
    manage.py ftt_basemap import field.pmtiles --name "Field, OSM" --event 3
    manage.py ftt_basemap import ortho.tif --attribution "Drone flight 2026-05-04"

``fetch`` runs again after an interruption and asks only for the missing tiles.
"""

from django.conf import settings
from django.core.exceptions import ValidationError
from django.core.management.base import BaseCommand, CommandError
from django.utils.translation import gettext as _

from basemaps.services import fetching, layers
from common.progress import ProgressBar
from events.models import TestEvent


def bbox(text: str) -> tuple[float, float, float, float]:
    parts = [float(v) for v in text.split(",")]
    if len(parts) != 4:
        raise ValueError("give west,south,east,north")
    return tuple(parts)


class Command(BaseCommand):
    help = "Download the tiles of an area into an archive, or register a basemap file."

    def add_arguments(self, parser):
        sub = parser.add_subparsers(dest="action", required=True)
        fetch = sub.add_parser("fetch", help="Download tiles of an area (while online).")
        fetch.add_argument("--bbox", required=True, help="west,south,east,north in degrees")
        fetch.add_argument("--zooms", required=True, help="e.g. 14-19")
        fetch.add_argument("--from", dest="url", required=True, help="URL with {z}/{x}/{y}")
        fetch.add_argument("out", help="Archive to write: NAME.pmtiles or NAME.mbtiles")
        fetch.add_argument(
            "--rate",
            type=float,
            default=settings.FTT_BASEMAP_FETCH_RATE,
            help="Tiles per second (FTT_BASEMAP_FETCH_RATE; mind the server's usage policy).",
        )
        fetch.add_argument("--max-tiles", type=int, default=20000)
        fetch.add_argument("--retries", type=int, default=3)
        fetch.add_argument("--attribution", default="", help="Whose map it is.")
        fetch.add_argument("--register", action="store_true", help="Also add it as a layer.")
        fetch.add_argument("--name", default="")
        imp = sub.add_parser("import", help="Register a GeoTIFF, MBTiles or PMTiles file.")
        imp.add_argument("file")
        imp.add_argument("--name", default="")
        imp.add_argument("--key", default="", help="Name in tile URLs (default from --name).")
        imp.add_argument("--attribution", default="")
        imp.add_argument("--event", type=int, help="Make it the default of this test event.")

    def handle(self, *args, action, **options):
        if action == "fetch":
            self.fetch(**options)
        else:
            self.register(options["file"], **options)

    def fetch(self, *, url, out, rate, max_tiles, retries, attribution, **options):
        bar = ProgressBar(self.stderr)
        try:
            result = fetching.fetch_area(
                url,
                bbox(options["bbox"]),
                fetching.parse_zooms(options["zooms"]),
                out,
                rate=rate,
                max_tiles=max_tiles,
                retries=retries,
                attribution=attribution,
                progress=lambda done, total: bar.count("tiles", done, total),
            )
        except ValueError as exc:
            raise CommandError(str(exc)) from exc
        except fetching.FetchError as exc:
            raise CommandError(
                _(
                    "Download interrupted (%(exc)s); the tiles so far are kept, run the "
                    "same command again to go on."
                )
                % {"exc": exc}
            ) from exc
        self.stdout.write(
            f"{result.path}: {result.total} tiles, {result.fetched} downloaded, "
            f"{result.already_there} from an earlier run, {result.missing} not on the server."
        )
        if options["register"]:
            self.register(out, name=options["name"], attribution=attribution)

    def register(self, path, *, name="", key="", attribution="", event=None, **_):
        test_event = None
        if event is not None:
            test_event = TestEvent.objects.filter(pk=event).first()
            if test_event is None:
                raise CommandError(_("No test event %(event)s.") % {"event": event})
        try:
            layer = layers.register_file(path, name=name, attribution=attribution, key=key)
        except (ValidationError, OSError) as exc:
            message = "; ".join(exc.messages) if isinstance(exc, ValidationError) else str(exc)
            raise CommandError(f"{path}: {message}") from exc
        if test_event is not None:
            layers.set_event_default(test_event, layer)
        self.stdout.write(
            f"Layer {layer.key!r} ({layer.get_kind_display()}), zoom {layer.min_zoom}-"
            f"{layer.max_zoom}, tiles at /tiles/{layer.key}/{{z}}/{{x}}/{{y}}.png"
        )
