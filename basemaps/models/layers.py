"""Map layers FTT draws under tracks: its own files or an external tile server."""

from django.core.validators import MaxValueValidator, MinValueValidator, RegexValidator
from django.db import models

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
        help_text="Short name used in tile URLs: /tiles/<key>/{z}/{x}/{y}.png",
    )
    name = models.CharField(max_length=200)
    kind = models.CharField(max_length=10, choices=KINDS)
    file = models.FileField(upload_to="basemaps/", blank=True, max_length=300)
    url = models.CharField(
        max_length=500,
        blank=True,
        validators=[
            RegexValidator(r"^https?://.*\{z\}.*\{x\}.*\{y\}", "Needs {z}, {x} and {y}."),
            check_tile_url,
        ],
        help_text="Only for external layers, e.g. https://tile.openstreetmap.org/{z}/{x}/{y}.png",
    )
    attribution = models.CharField(max_length=300, blank=True)
    enabled = models.BooleanField(
        default=True,
        help_text="Offered in the maps and used as a test event's default. An external "
        "layer that came with an imported archive arrives off until an administrator "
        "checks its address and turns it on.",
    )
    min_zoom = models.PositiveSmallIntegerField(default=0, validators=zoom_validators)
    max_zoom = models.PositiveSmallIntegerField(default=19, validators=zoom_validators)
    # Bounds in WGS 84 degrees, read from the file; empty for external layers.
    west = models.FloatField(null=True, blank=True)
    south = models.FloatField(null=True, blank=True)
    east = models.FloatField(null=True, blank=True)
    north = models.FloatField(null=True, blank=True)
    # What an archive stores ("png", "jpg", "webp"); rasters render on demand.
    tile_format = models.CharField(max_length=10, blank=True)
    modified = models.DateTimeField(auto_now=True)

    class Meta:
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
        "events.TestEvent", on_delete=models.CASCADE, related_name="basemap"
    )
    layer = models.ForeignKey(BasemapLayer, on_delete=models.CASCADE, related_name="events")

    class Meta:
        verbose_name = "default basemap of a test event"
        verbose_name_plural = "default basemaps of test events"

    def __str__(self):
        return f"{self.test_event}: {self.layer}"
