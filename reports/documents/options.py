"""What may be asked of a report, and the error when it cannot be made."""

from dataclasses import dataclass, field

from django.conf import settings
from django.utils.translation import gettext as _
from django.utils.translation import gettext_lazy

from common.deferred_text import DeferredText
from reports.charts.tiles import MAX_ZOOM

MAX_TIMELINE_HOURS = 48

# How much of each shift the report shows: the GUI dialog, the API and the
# command offer these choices (value, what a person reads).
SUMMARY, STANDARD, FULL = "summary", "standard", "full"
LEVELS = (
    (SUMMARY, gettext_lazy("Summary: event and shift pages only")),
    (STANDARD, gettext_lazy("Standard: plus one compact block per intervention (ITO)")),
    (FULL, gettext_lazy("Full: every segment with its map")),
)


class ReportError(Exception):
    """The report cannot be made; the message says why in words for a person.

    Raised with the English text (marked with gettext_noop) and its values, kept
    as ``deferred``, so the job's row shows it in its reader's language; ``str()`` is
    the active language's. A refusal passed on from a check that already said it
    (a route that cannot be drawn) stays in the language it was said in."""

    def __init__(self, text: str, **values):
        self.deferred = DeferredText(text, values)
        super().__init__(text)

    def __str__(self) -> str:
        return str(self.deferred)


@dataclass
class ReportOptions:
    name: str = ""
    version: str = "1.0"
    recipient: str = ""
    recipient_address: list[str] = field(default_factory=list)
    creator: str = ""
    creator_address: list[str] = field(default_factory=list)
    local: bool = False
    tile_url: str | None = None  # None: the site's FTT_TILE_URL
    no_tiles: bool = False
    logo: str | None = None
    # The original's min_dur: a short shift's timeline still spans this many
    # hours, so timelines of several reports can be compared by eye.
    min_timeline_hours: float = 0.0
    # The original's zoom_level, as an upper bound: the zoom is still fitted to
    # each track, but never closer than this (a tile server may stop at 17).
    max_zoom: int = MAX_ZOOM
    level: str = FULL
    # Camera frames appear as thumbnails; with this each links to a full-size
    # copy in an appendix (without it the report stays shorter).
    image_appendix: bool = True
    # The report's language (settings.LANGUAGES); empty: the test event's.
    language: str = ""
    # A report of one shift or one leg (ids) instead of the whole test event; a
    # leg brings its shift (reports/selectors/content.py report_scope checks both).
    shift: int | None = None
    leg: int | None = None

    @property
    def scope(self) -> dict:
        """The shift and leg the report is narrowed to, as selectors take them."""
        return {"shift": self.shift, "leg": self.leg}

    def problems(self) -> list[str]:
        """What is out of range, in words for the person who asked."""
        found = []
        if not 0 <= self.min_timeline_hours <= MAX_TIMELINE_HOURS:
            found.append(
                _("The minimum timeline length must be between 0 and %(hours)s hours.")
                % {"hours": MAX_TIMELINE_HOURS}
            )
        if not 1 <= self.max_zoom <= MAX_ZOOM:
            found.append(
                _("The maximum map zoom must be between 1 and %(zoom)s.") % {"zoom": MAX_ZOOM}
            )
        if problem := language_problem(self.language):
            found.append(problem)
        if self.level not in dict(LEVELS):
            found.append(
                _("The level must be one of %(levels)s.") % {"levels": ", ".join(dict(LEVELS))}
            )
        return found

    @classmethod
    def from_dict(cls, data: dict) -> "ReportOptions":
        known = {k: v for k, v in (data or {}).items() if k in cls.__dataclass_fields__}
        return cls(**known)

    def as_dict(self) -> dict:
        return {k: getattr(self, k) for k in self.__dataclass_fields__}


def language_problem(language: str) -> str | None:
    """Why ``language`` cannot be a report's language; empty means the default."""
    if language and language not in dict(settings.LANGUAGES):
        return _("The language must be one of %(languages)s.") % {
            "languages": ", ".join(dict(settings.LANGUAGES))
        }
    return None
