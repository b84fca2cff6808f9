"""Track maps for the report.

GPS tracks are drawn in a local azimuthal-equidistant frame (metres east and
north of the track's centre), so distances on the page are true and a metric
grid and scale bar mean something.  Tiles (Web Mercator) are placed under it
by projecting the mosaic's corners; over the few kilometres of a field test
the difference between the two projections is far below a pixel.

Local tracks are drawn in the map frame over the occupancy map, which is
placed with its origin and turned by its yaw about that origin (ROS map
convention: the image's bottom-left pixel is the origin).
"""

from dataclasses import dataclass, field

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from django.utils.translation import gettext as _  # noqa: E402
from matplotlib.collections import LineCollection  # noqa: E402
from matplotlib.ticker import MaxNLocator  # noqa: E402
from matplotlib.transforms import Affine2D  # noqa: E402

from reports import formatting as fmt  # noqa: E402
from reports.charts import style  # noqa: E402
from reports.charts.style import rgb  # noqa: E402
from reports.projection import local_frame  # noqa: E402
from telemetry.selectors.track_drawing import simplified  # noqa: E402
from telemetry.storage.keys import GPS_TRACK  # noqa: E402

PAD_FRACTION = 0.1
PAD_MIN_M = 10.0
# Where the map's axes sit in its figure, as fractions of the figure's width.
AXES_LEFT, AXES_RIGHT = 0.13, 0.97
DPI = 150


@dataclass
class Line:
    x: list[float]
    y: list[float]
    color: str  # "R,G,B" as in the catalogues
    width: float = 2.0


@dataclass
class MapResult:
    path: str
    tiles: bool
    note: str = ""


@dataclass
class Background:
    """The occupancy map under local tracks."""

    image: np.ndarray  # H x W (x 3) array, first row at the top
    resolution: float
    origin_x: float
    origin_y: float
    origin_yaw: float


@dataclass
class MapPainter:
    tiles: object | None = None  # reports.charts.tiles.TileSource
    dpi: int = DPI
    tiles_used: set = field(default_factory=set)

    def gps_map(self, lines: list[Line], path: str, size=(6.0, 4.5)) -> MapResult | None:
        if not any(len(line.x) for line in lines):
            return None
        forward, back = _frame(lines)
        projected = _projected(lines, forward)
        bounds = _padded_bounds(projected, size)
        fig, ax = _figure(size)
        tiles = False
        if self.tiles is not None:
            w, s = back.transform(bounds[0], bounds[2])
            e, n = back.transform(bounds[1], bounds[3])
            mosaic = self.tiles.mosaic(w, s, e, n)
            if mosaic is not None:
                array, (mw, ms, me, mn), _zoom = mosaic
                x0, y1 = forward.transform(mw, mn)
                x1, y0 = forward.transform(me, ms)
                ax.imshow(array, extent=(x0, x1, y0, y1), interpolation="bilinear", zorder=0)
                tiles = True
        note = (
            ""
            if tiles
            else _plain(ax, _("Map tiles unavailable: plain background, grid in metres."))
        )
        _finish(ax, projected, bounds, _("east [m]"), _("north [m]"), self.dpi)
        _north_arrow(ax)
        _save(fig, path, self.dpi)
        return MapResult(path, tiles, note)

    def local_map(
        self, lines: list[Line], background: Background | None, path: str, size=(6.0, 4.5)
    ) -> MapResult | None:
        if not any(len(line.x) for line in lines):
            return None
        bounds = _padded_bounds(lines, size)
        fig, ax = _figure(size)
        note = ""
        if background is not None:
            h, w = background.image.shape[:2]
            ox, oy = background.origin_x, background.origin_y
            extent = (ox, ox + w * background.resolution, oy, oy + h * background.resolution)
            turn = Affine2D().rotate_around(ox, oy, background.origin_yaw)
            ax.imshow(
                background.image,
                extent=extent,
                cmap="gray",
                vmin=0,
                vmax=255,
                origin="upper",
                interpolation="nearest",
                transform=turn + ax.transData,
                zorder=0,
            )
            # The map origin, so a reader can check where the grid is anchored.
            ax.plot([ox], [oy], "k+", markersize=8, zorder=4)
        else:
            note = _plain(ax, _("No occupancy map recorded for this shift."))
        _finish(ax, lines, bounds, _("x [m] (map frame)"), _("y [m] (map frame)"), self.dpi)
        _save(fig, path, self.dpi)
        return MapResult(path, background is not None, note)


def _figure(size):
    # Fixed margins: a constrained layout would cost half the time of a map,
    # and a report has one map per segment.
    fig, ax = style.new_chart(size)
    fig.subplots_adjust(left=AXES_LEFT, right=AXES_RIGHT, bottom=0.12, top=0.97)
    ax.tick_params(labelsize=7)
    return fig, ax


def _padded_bounds(lines: list[Line], size) -> tuple[float, float, float, float]:
    """The tracks' box, padded, then widened to the figure's shape so that an
    equal-aspect axis fills the figure (and the tiles cover all of it)."""
    xs = np.concatenate([np.asarray(ln.x, dtype=float) for ln in lines if len(ln.x)])
    ys = np.concatenate([np.asarray(ln.y, dtype=float) for ln in lines if len(ln.y)])
    x0, x1, y0, y1 = xs.min(), xs.max(), ys.min(), ys.max()
    pad = max(PAD_FRACTION * (x1 - x0), PAD_FRACTION * (y1 - y0), PAD_MIN_M)
    x0, x1, y0, y1 = x0 - pad, x1 + pad, y0 - pad, y1 + pad
    shape = size[0] / size[1]
    width, height = x1 - x0, y1 - y0
    if width / height < shape:
        grow = (height * shape - width) / 2
        x0, x1 = x0 - grow, x1 + grow
    else:
        grow = (width / shape - height) / 2
        y0, y1 = y0 - grow, y1 + grow
    return (x0, x1, y0, y1)


def drawing_tolerance(bounds, size, dpi: int = DPI) -> float:
    """Half a pixel of a map of ``size`` inches showing ``bounds``: what its tracks
    are thinned by, since nothing finer can be seen (also what the retention
    policy thins stored poses to, reports.services.pose_retention)."""
    pixels = (AXES_RIGHT - AXES_LEFT) * size[0] * dpi
    return (bounds[1] - bounds[0]) / pixels / 2


def map_tolerance(mode: str, lines: list[Line], size) -> tuple[float, list[Line]]:
    """The tolerance a map of ``lines`` (GPS: longitude, latitude) thins them by,
    and the lines in the map's units (metres) that it applies to."""
    if mode == GPS_TRACK:
        lines = _projected(lines)
    return drawing_tolerance(_padded_bounds(lines, size), size), lines


def _frame(lines: list[Line]):
    """The local frame (forward, back) around the centre of GPS lines."""
    lons = np.concatenate([np.asarray(line.x, dtype=float) for line in lines])
    lats = np.concatenate([np.asarray(line.y, dtype=float) for line in lines])
    return local_frame(float((lons.min() + lons.max()) / 2), float((lats.min() + lats.max()) / 2))


def _projected(lines: list[Line], forward=None) -> list[Line]:
    """GPS lines in metres east and north of their common centre."""
    forward = forward or _frame(lines)[0]
    return [Line(*forward.transform(ln.x, ln.y), ln.color, ln.width) for ln in lines]


def _draw_lines(ax, lines: list[Line], tolerance: float):
    """All tracks as one line collection and their starts as one scatter: a shift
    has dozens of segments, and two artists per segment were most of a map's time."""
    drawn = [line for line in lines if len(line.x)]
    if not drawn:
        return
    paths = []
    for line in drawn:
        # A shift's track has tens of thousands of points; those closer than
        # half a pixel to the line cannot be seen and only cost drawing time.
        x, y = simplified(np.asarray(line.x, float), np.asarray(line.y, float), tolerance)
        paths.append(np.column_stack([x, y]))
    colors = [rgb(line.color) for line in drawn]
    ax.add_collection(
        LineCollection(
            paths,
            colors=colors,
            linewidths=[line.width for line in drawn],
            zorder=2,
            capstyle="round",
            joinstyle="round",
        )
    )
    ax.scatter(
        [line.x[0] for line in drawn],
        [line.y[0] for line in drawn],
        s=16,
        color=colors,
        edgecolors="black",
        linewidths=0.8,
        zorder=3,
    )


def _plain(ax, note: str) -> str:
    # The note is printed once, under the map, by the report; not inside the image.
    ax.set_facecolor("#f2f1ec")
    return note


def _save(fig, path, dpi):
    fig.savefig(path, dpi=dpi)
    plt.close(fig)


def _finish(ax, lines, bounds, xlabel, ylabel, dpi):
    """Grid, tracks, limits, labels and scale bar: what every map has."""
    ax.grid(True, color="#888888", linewidth=0.4, alpha=0.6)
    x0, x1, y0, y1 = bounds
    _draw_lines(ax, lines, drawing_tolerance(bounds, ax.figure.get_size_inches(), dpi))
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    ax.set_aspect("equal", adjustable="box")
    ax.set_xlabel(xlabel, fontsize=7)
    ax.set_ylabel(ylabel, fontsize=7)
    # Few ticks: the grid is for orientation, and tick labels dominate drawing time.
    ax.xaxis.set_major_locator(MaxNLocator(5))
    ax.yaxis.set_major_locator(MaxNLocator(5))
    _scale_bar(ax)


def nice_length(span: float) -> float:
    target = span / 5
    magnitude = 10 ** np.floor(np.log10(max(target, 1e-6)))
    for factor in (1, 2, 5, 10):
        if factor * magnitude >= target:
            return float(factor * magnitude)
    return float(10 * magnitude)


def scale_label(length: float) -> str:
    """A scale bar's length in m or km, in the report's language."""
    return fmt.number(length) + " m" if length < 1000 else fmt.number(length / 1000) + " km"


def _scale_bar(ax):
    x0, x1, y0, y1 = ax.get_xlim() + ax.get_ylim()
    length = nice_length(x1 - x0)
    bx = x0 + 0.05 * (x1 - x0)
    by = y0 + 0.06 * (y1 - y0)
    ax.plot([bx, bx + length], [by, by], color="black", linewidth=3, zorder=5)
    ax.plot([bx, bx + length], [by, by], color="white", linewidth=1, zorder=6)
    ax.text(
        bx + length / 2,
        by + 0.02 * (y1 - y0),
        scale_label(length),
        ha="center",
        fontsize=7,
        zorder=6,
    )


def _north_arrow(ax):
    ax.annotate(
        "N",
        xy=(0.95, 0.95),
        xytext=(0.95, 0.84),
        xycoords="axes fraction",
        ha="center",
        va="center",
        fontsize=9,
        fontweight="bold",
        arrowprops={"arrowstyle": "-|>", "color": "black", "lw": 1.5},
        zorder=7,
    )
