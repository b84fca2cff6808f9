"""Weather symbols for the timeline, drawn as vector shapes.

The original report pasted third-party PNG icons above each shift's bar; these
are our own, drawn from the catalogue's ``icon`` key, so they scale with the
figure and need no image files. An unknown key gets a question mark.
"""

import math

from matplotlib.lines import Line2D
from matplotlib.offsetbox import AnnotationBbox, DrawingArea
from matplotlib.patches import Circle, FancyBboxPatch
from matplotlib.text import Text

SIZE = 22  # points; the box each symbol is drawn in
SUN = "#f2b705"
CLOUD_LIGHT = "#c9ced6"
CLOUD_DARK = "#7d8590"
WATER = "#1f77b4"
OUTLINE = "#4d4d4d"


def _sun(area: DrawingArea, cx: float, cy: float, radius: float) -> None:
    for i in range(8):
        angle = i * math.pi / 4
        inner, outer = radius * 1.35, radius * 1.9
        area.add_artist(
            Line2D(
                [cx + inner * math.cos(angle), cx + outer * math.cos(angle)],
                [cy + inner * math.sin(angle), cy + outer * math.sin(angle)],
                color=SUN,
                linewidth=1.2,
                solid_capstyle="round",
            )
        )
    area.add_artist(Circle((cx, cy), radius, facecolor=SUN, edgecolor=OUTLINE, linewidth=0.4))


def _cloud(area: DrawingArea, x: float, y: float, width: float, color: str) -> None:
    """A cloud whose flat base starts at (x, y)."""
    height = width * 0.28
    for dx, dy, r in ((0.3, 0.3, 0.22), (0.58, 0.42, 0.28), (0.8, 0.25, 0.18)):
        area.add_artist(
            Circle(
                (x + dx * width, y + dy * width),
                r * width,
                facecolor=color,
                edgecolor=OUTLINE,
                linewidth=0.4,
            )
        )
    area.add_artist(
        FancyBboxPatch(
            (x + 0.1 * width, y),
            width * 0.8,
            height,
            boxstyle=f"round,pad=0,rounding_size={height / 2}",
            facecolor=color,
            edgecolor="none",
        )
    )


def _marks(area: DrawingArea, y: float, mark) -> None:
    for x in (SIZE * 0.3, SIZE * 0.5, SIZE * 0.7):
        mark(x, y)


def _drop(area: DrawingArea):
    def draw(x, y):
        area.add_artist(Line2D([x + 1.2, x - 1.2], [y + 2.5, y - 2.5], color=WATER, linewidth=1.1))

    return draw


def _flake(area: DrawingArea):
    def draw(x, y):
        for angle in (0, math.pi / 3, 2 * math.pi / 3):
            dx, dy = 2.4 * math.cos(angle), 2.4 * math.sin(angle)
            area.add_artist(Line2D([x - dx, x + dx], [y - dy, y + dy], color=WATER, linewidth=0.7))

    return draw


def symbol(icon: str) -> DrawingArea:
    """The weather symbol for a catalogue icon key (sun, cloudy, overcast, fog, rain, snow)."""
    area = DrawingArea(SIZE, SIZE)
    s = SIZE
    if icon == "sun":
        _sun(area, s / 2, s / 2, s * 0.2)
    elif icon == "cloudy":
        _sun(area, s * 0.62, s * 0.64, s * 0.15)
        _cloud(area, s * 0.05, s * 0.18, s * 0.8, CLOUD_LIGHT)
    elif icon == "overcast":
        _cloud(area, s * 0.2, s * 0.42, s * 0.75, CLOUD_DARK)
        _cloud(area, s * 0.02, s * 0.15, s * 0.8, CLOUD_LIGHT)
    elif icon == "fog":
        _cloud(area, s * 0.1, s * 0.45, s * 0.8, CLOUD_LIGHT)
        for y in (s * 0.12, s * 0.26, s * 0.4):
            area.add_artist(Line2D([s * 0.1, s * 0.9], [y, y], color=CLOUD_DARK, linewidth=1.1))
    elif icon == "rain":
        _cloud(area, s * 0.1, s * 0.45, s * 0.8, CLOUD_DARK)
        _marks(area, s * 0.22, _drop(area))
    elif icon == "snow":
        _cloud(area, s * 0.1, s * 0.45, s * 0.8, CLOUD_LIGHT)
        _marks(area, s * 0.22, _flake(area))
    else:
        area.add_artist(
            Text(s / 2, s / 2, "?", ha="center", va="center", fontsize=11, color=OUTLINE)
        )
    return area


def place(ax, when, row: float, icon: str) -> None:
    """Put the symbol for ``icon`` on the axes at time ``when`` and y ``row``."""
    ax.add_artist(
        AnnotationBbox(
            symbol(icon),
            (when, row),
            xycoords="data",
            frameon=False,
            box_alignment=(0.0, 0.5),
            pad=0,
            annotation_clip=False,
        )
    )
