"""Colours and fonts shared by every report figure."""

import logging

import matplotlib
from matplotlib import font_manager

# Latin/Greek/Cyrillic first, then CJK fonts; matplotlib falls back glyph by
# glyph along this list, so a reason or name in any of them renders.
FONT_FAMILIES = ("DejaVu Sans", "WenQuanYi Micro Hei", "Noto Sans CJK JP", "Noto Sans CJK SC")


def rgb(value: str, default=(0.5, 0.5, 0.5)) -> tuple[float, float, float]:
    """Catalogue colour 'R,G,B' (0-255) as a matplotlib colour."""
    try:
        r, g, b = (int(part) for part in value.split(","))
    except (AttributeError, ValueError):
        return default
    return (r / 255, g / 255, b / 255)


def installed_families() -> list[str]:
    names = {f.name for f in font_manager.fontManager.ttflist}
    return [family for family in FONT_FAMILIES if family in names] or ["DejaVu Sans"]


def apply() -> None:
    # The CJK fonts have no bold face; matplotlib says so on every bold label.
    logging.getLogger("matplotlib.font_manager").setLevel(logging.ERROR)
    matplotlib.rcParams["font.family"] = installed_families()
    matplotlib.rcParams["axes.titlesize"] = 9
    # Text stays text in SVG charts (typst sets it), instead of outlines.
    matplotlib.rcParams["svg.fonttype"] = "none"
