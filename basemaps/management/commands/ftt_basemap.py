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
        raise ValueError(_("Give the box as west,south,east,north in degrees."))
    return tuple(parts)


class Command(BaseCommand):
    help = _("Download the tiles of an area into an archive, or register a basemap file.")

    def add_arguments(self, parser):
        sub = parser.add_subparsers(dest="action", required=True)
        fetch = sub.add_parser("fetch", help=_("Download tiles of an area (while online)."))
        fetch.add_argument("--bbox", required=True, help=_("west,south,east,north in degrees"))
        fetch.add_argument("--zooms", required=True, help=_("e.g. 14-19"))
        fetch.add_argument("--from", dest="url", required=True, help=_("URL with {z}/{x}/{y}"))
        fetch.add_argument("out", help=_("Archive to write: NAME.pmtiles or NAME.mbtiles"))
        fetch.add_argument(
            "--rate",
            type=float,
            default=settings.FTT_BASEMAP_FETCH_RATE,
            help=_("Tiles per second (FTT_BASEMAP_FETCH_RATE; mind the server's usage policy)."),
        )
        fetch.add_argument(
            "--max-tiles", type=int, default=20000, help=_("Refuse an area of more tiles.")
        )
        fetch.add_argument(
            "--retries",
            type=int,
            default=3,
            help=_("Retries per tile after the first attempt, before giving up."),
        )
        fetch.add_argument("--attribution", default="", help=_("Whose map it is."))
        fetch.add_argument("--register", action="store_true", help=_("Also add it as a layer."))
        fetch.add_argument("--name", default="", help=_("Name of the layer."))
        imp = sub.add_parser("import", help=_("Register a GeoTIFF, MBTiles or PMTiles file."))
        imp.add_argument("file", help=_("The GeoTIFF, MBTiles or PMTiles file."))
        imp.add_argument("--name", default="", help=_("Name of the layer."))
        imp.add_argument("--key", default="", help=_("Name in tile URLs (default from --name)."))
        imp.add_argument("--attribution", default="", help=_("Whose map it is."))
        imp.add_argument("--event", type=int, help=_("Make it the default of this test event."))

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
                progress=lambda done, total: bar.count(_("tiles"), done, total),
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
            _(
                "%(path)s: %(total)s tiles, %(fetched)s downloaded, %(earlier)s from an "
                "earlier run, %(missing)s not on the server."
            )
            % {
                "path": result.path,
                "total": result.total,
                "fetched": result.fetched,
                "earlier": result.already_there,
                "missing": result.missing,
            }
        )
        if options["register"]:
            self.register(out, name=options["name"], attribution=attribution)

    def register(self, path, *, name="", key="", attribution="", event=None, **_options):
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
            _("Layer '%(key)s' (%(kind)s), zoom %(min)s-%(max)s, tiles at %(url)s")
            % {
                "key": layer.key,
                "kind": layer.get_kind_display(),
                "min": layer.min_zoom,
                "max": layer.max_zoom,
                "url": f"/tiles/{layer.key}/{{z}}/{{x}}/{{y}}.png",
            }
        )
