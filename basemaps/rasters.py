"""GeoTIFFs are data, not programs: how FTT opens a raster basemap.

GDAL opens far more than GeoTIFF: a VRT (an XML file) may name any file the
server can read or a ``/vsicurl/`` address it will fetch, and even a GeoTIFF
makes GDAL look for sibling files (``.aux.xml``, ``.ovr``). So a raster layer
is a regular file that starts like a TIFF, never a ``/vsi…`` path, opened with
the GeoTIFF driver only, and the whole process runs GDAL with network and
sibling-file access off (basemaps.confinement, applied when the app loads).
"""

from pathlib import Path

import rasterio
from django.utils.translation import gettext as _
from rasterio.errors import RasterioError
from rio_tiler.io import Reader

# Classic TIFF and BigTIFF, little- and big-endian.
TIFF_MAGIC = (b"II*\x00", b"MM\x00*", b"II+\x00", b"MM\x00+")


class NotAGeoTiff(ValueError):
    pass


def check_local_file(path) -> Path:
    """The path of a regular local file, never a GDAL virtual path or an address."""
    text = str(path)
    if "/vsi" in text.lower() or "://" in text:
        raise NotAGeoTiff(
            _("%(path)s is a GDAL virtual path or an address, not a file.") % {"path": text[:200]}
        )
    path = Path(path)
    if not path.is_file():
        raise NotAGeoTiff(_("%(path)s is not a regular file.") % {"path": text[:200]})
    return path


def check_geotiff_path(path) -> Path:
    """The path of a regular local file that starts like a TIFF; else NotAGeoTiff."""
    path = check_local_file(path)
    with path.open("rb") as f:
        if not f.read(4).startswith(TIFF_MAGIC):
            raise NotAGeoTiff(_("not a TIFF file"))
    return path


def open_geotiff(path):
    """A rasterio dataset of a checked GeoTIFF, opened with the GeoTIFF driver only."""
    try:
        return rasterio.open(check_geotiff_path(path), driver="GTiff")
    except RasterioError as exc:
        raise NotAGeoTiff(str(exc).splitlines()[0][:200]) from None


class GeoTiffTiles:
    """rio-tiler's reader over :func:`open_geotiff`'s dataset, closed together."""

    def __init__(self, path):
        self.dataset = open_geotiff(path)
        try:
            self.reader = Reader(None, dataset=self.dataset)
        except Exception:
            self.dataset.close()
            raise

    def tile(self, x, y, z):
        return self.reader.tile(x, y, z)

    def close(self):
        self.reader.close()
        self.dataset.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
