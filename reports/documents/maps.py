"""The report's maps of tracks: where their tiles come from, drawing them, and the
methods page's note on the tiles."""

from pathlib import Path

from django.conf import settings
from django.utils.translation import gettext as _
from django.utils.translation import gettext_noop

from basemaps.selectors.layers import default_layer
from reports.charts.maps import Line, MapPainter
from reports.charts.tiles import LayerTiles, TileSource
from reports.documents.options import ReportOptions
from reports.documents.pictures import Pictures
from telemetry.storage.keys import GPS_TRACK, LOCAL_TRACK


def tile_source(event, options: ReportOptions, mode: str) -> TileSource | LayerTiles | None:
    """A tile URL given for this report, else the event's basemap, else the site's."""
    if options.no_tiles or mode == LOCAL_TRACK:
        return None
    tile_url = options.tile_url
    if tile_url is None:
        layer = default_layer(event.pk)
        if layer is not None and layer.served_by_ftt:
            return LayerTiles(layer, max_zoom=options.max_zoom)
        tile_url = layer.url if layer is not None else settings.FTT_TILE_URL
    if not tile_url:
        return None
    cache = Path(getattr(settings, "FTT_TILE_CACHE", settings.DATA_DIR / "tile_cache"))
    return TileSource(tile_url, cache, max_zoom=options.max_zoom)


def _type_color(kind: str) -> str:
    return {"auto": "44,160,44", "unknown": "150,150,150"}.get(kind, "214,39,40")


class TrackMaps:
    """Draws runs on tiles (GPS) or on the shift's map image (local frame)."""

    def __init__(self, mode: str, tiles, pictures: Pictures, time_stage):
        self.mode = mode
        self.tiles = tiles
        self.painter = MapPainter(tiles=tiles)
        self.pictures = pictures
        self.time_stage = time_stage
        self.tiles_used = False

    def draw(self, runs, shift, new_file, size) -> tuple[str | None, str]:
        """(file name, note) of the map of ``runs``; ``new_file(stem)`` names its file."""
        with self.time_stage(gettext_noop("figures: maps")):
            lines = [
                Line(run.path_x, run.path_y, _type_color(run.kind))
                for run in runs
                if len(run.path_x)
            ]
            if not lines:
                return None, _("No positions recorded.")
            path = str(new_file("map"))
            if self.mode == GPS_TRACK:
                result = self.painter.gps_map(lines, path, size=size)
            else:
                background = self.pictures.background(shift)
                result = self.painter.local_map(lines, background, path, size=size)
            if result is None:
                return None, _("No positions recorded.")
            if self.mode == GPS_TRACK and result.tiles:
                self.tiles_used = True
            return Path(result.path).name, result.note

    def tiles_note(self) -> str:
        if self.mode != GPS_TRACK:
            return ""
        if self.tiles is None:
            return _(
                "Map tiles were switched off: maps show a plain background with a "
                "metric grid, scale bar and north arrow."
            )
        if not self.tiles_used:
            return _(
                "Map tiles were unavailable (tile server unreachable): maps show a plain "
                "background with a metric grid, scale bar and north arrow."
            )
        if isinstance(self.tiles, LayerTiles):
            return _("Map: %(url)s, drawn by FTT from its own basemap file.") % {
                "url": self.tiles.url
            }
        return _(
            "Map tiles: %(url)s (%(fetched)s fetched, %(cached)s from the local cache). "
            "Map data © their owners, e.g. OpenStreetMap contributors."
        ) % {"url": self.tiles.url, "fetched": self.tiles.fetched, "cached": self.tiles.from_cache}
