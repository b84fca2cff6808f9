"""Map layers FTT draws under tracks: its own files or an external tile server."""

from django.core.validators import MaxValueValidator, MinValueValidator, RegexValidator
from django.db import models
from django.utils.translation import gettext_lazy as _

from basemaps.hosts import check_tile_url

MAX_ZOOM = 24
zoom_validators = [MinValueValidator(0), MaxValueValidator(MAX_ZOOM)]


class BasemapLayer(models.Model):
    RASTER = "raster"
    MBTILES = "mbtiles"
    PMTILES = "pmtiles"
    URL = "url"
    KINDS = [
        (RASTER, "GeoTIFF / Cloud-Optimized GeoTIFF"),
        (MBTILES, "MBTiles archive"),
        (PMTILES, "PMTiles archive"),
        (URL, "External XYZ tile server"),
    ]

    key = models.SlugField(
        unique=True,
        max_length=60,
        help_text=_("Short name used in tile URLs: /tiles/<key>/{z}/{x}/{y}.png"),
        verbose_name=_("key"),
    )
    name = models.CharField(max_length=200, verbose_name=_("name"))
    kind = models.CharField(max_length=10, choices=KINDS, verbose_name=_("kind"))
    file = models.FileField(
        upload_to="basemaps/", blank=True, max_length=300, verbose_name=_("file")
    )
    url = models.CharField(
        max_length=500,
        blank=True,
        validators=[
            RegexValidator(r"^https?://.*\{z\}.*\{x\}.*\{y\}", "Needs {z}, {x} and {y}."),
            check_tile_url,
        ],
        help_text=_(
            "Only for external layers, e.g. https://tile.openstreetmap.org/{z}/{x}/{y}.png"
        ),
        verbose_name=_("url"),
    )
    attribution = models.CharField(max_length=300, blank=True, verbose_name=_("attribution"))
    enabled = models.BooleanField(
        default=True,
        help_text=_(
            "Offered in the maps and used as a test event's default. An external "
            "layer that came with an imported archive arrives off until an administrator "
            "checks its address and turns it on."
        ),
        verbose_name=_("enabled"),
    )
    min_zoom = models.PositiveSmallIntegerField(
        default=0, validators=zoom_validators, verbose_name=_("min zoom")
    )
    max_zoom = models.PositiveSmallIntegerField(
        default=19, validators=zoom_validators, verbose_name=_("max zoom")
    )
    # Bounds in WGS 84 degrees, read from the file; empty for external layers.
    west = models.FloatField(null=True, blank=True, verbose_name=_("west"))
    south = models.FloatField(null=True, blank=True, verbose_name=_("south"))
    east = models.FloatField(null=True, blank=True, verbose_name=_("east"))
    north = models.FloatField(null=True, blank=True, verbose_name=_("north"))
    # What an archive stores ("png", "jpg", "webp"); rasters render on demand.
    tile_format = models.CharField(max_length=10, blank=True, verbose_name=_("tile format"))
    modified = models.DateTimeField(auto_now=True, verbose_name=_("modified"))

    class Meta:
        verbose_name = _("basemap layer")
        verbose_name_plural = _("basemap layers")
        ordering = ["name"]
        constraints = [
            models.CheckConstraint(
                condition=models.Q(min_zoom__lte=models.F("max_zoom")),
                name="basemap_zoom_order",
            ),
        ]

    def __str__(self):
        return self.name

    @property
    def served_by_ftt(self) -> bool:
        return self.kind != self.URL

    @property
    def bounds(self) -> tuple[float, float, float, float] | None:
        if self.west is None:
            return None
        return (self.west, self.south, self.east, self.north)


class EventBasemap(models.Model):
    """The layer a test event's maps start on (GUI) and are drawn on (report).

    Kept on this side so that the logbook (``events``) knows nothing of basemaps.
    """

    test_event = models.OneToOneField(
        "events.TestEvent",
        on_delete=models.CASCADE,
        related_name="basemap",
        verbose_name=_("test event"),
    )
    layer = models.ForeignKey(
        BasemapLayer, on_delete=models.CASCADE, related_name="events", verbose_name=_("layer")
    )

    class Meta:
        verbose_name = _("default basemap of a test event")
        verbose_name_plural = _("default basemaps of test events")

    def __str__(self):
        return f"{self.test_event}: {self.layer}"
