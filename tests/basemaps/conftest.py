import pytest

from basemaps.services import layers
from tests.support.basemaps import quadrant_geotiff


@pytest.fixture
def orthophoto(db, media_root, tmp_path):
    """A registered GeoTIFF layer in UTM 32N with four coloured quadrants."""
    return layers.register_file(
        quadrant_geotiff(tmp_path / "ortho.tif"), name="Orthophoto", attribution="Drone"
    )


@pytest.fixture
def viewer_client(client, role_user):
    client.force_login(role_user("viewer"))
    return client
