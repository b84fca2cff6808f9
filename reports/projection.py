"""The local metric frame GPS positions are drawn and measured in on a map.

Azimuthal equidistant around a centre: metres east and north, true distances
from the centre and, over the few kilometres of a test site, between points.
"""

from dataclasses import dataclass
from functools import lru_cache

from pyproj import Transformer
from pyproj.enums import TransformDirection


@dataclass(frozen=True)
class _Inverse:
    transformer: Transformer

    def transform(self, x, y):
        return self.transformer.transform(x, y, direction=TransformDirection.INVERSE)


@lru_cache(maxsize=64)
def _aeqd(lon0: float, lat0: float):
    # A PROJ pipeline string needs no lookup in PROJ's CRS database (slow per
    # frame, docs/report.md) and gives the same coordinates as the CRS would.
    pipeline = Transformer.from_pipeline(
        "+proj=pipeline +step +proj=unitconvert +xy_in=deg +xy_out=rad "
        f"+step +proj=aeqd +lat_0={lat0} +lon_0={lon0} +ellps=WGS84"
    )
    return pipeline, _Inverse(pipeline)


def local_frame(lon: float, lat: float):
    """The local frame around a point, shared by maps whose centres are within
    about a kilometre: the frame's scale error there is below 1e-7."""
    return _aeqd(round(lon, 2), round(lat, 2))
