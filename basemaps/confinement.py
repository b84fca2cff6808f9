"""GDAL's configuration for files from strangers (gdal.org, "Security
considerations" and the configuration options list).

Set in the environment when the app loads (basemaps.apps), so it applies
wherever GDAL is loaded, before or after, without loading it here.
"""

import os

GDAL_CONFINEMENT = {
    # Do not list the directory or probe for sibling files on open.
    "GDAL_DISABLE_READDIR_ON_OPEN": "EMPTY_DIR",
    # No .aux.xml side files read or written.
    "GDAL_PAM_ENABLED": "NO",
    # /vsicurl/ and friends open nothing (no address ends like this).
    "CPL_VSIL_CURL_ALLOWED_EXTENSIONS": ".ftt-no-network",
    "GDAL_HTTP_TIMEOUT": "1",
    "GDAL_HTTP_MAX_RETRY": "0",
    # Should a VRT ever be opened: no raw files, no Python.
    "GDAL_VRT_ENABLE_RAWRASTERBAND": "NO",
    "GDAL_VRT_ENABLE_PYTHON": "NO",
}


def confine_gdal() -> None:
    os.environ.update(GDAL_CONFINEMENT)
