"""The tile grid every map of FTT uses: Web Mercator (EPSG:3857) in 256-pixel
tiles numbered from the north-west, as OpenStreetMap and Leaflet number them.
morecantile holds the arithmetic; this is its one instance."""

import morecantile

WEB_MERCATOR = morecantile.tms.get("WebMercatorQuad")
TILE_SIZE = 256
