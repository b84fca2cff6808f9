import io
import math
from types import SimpleNamespace as NS

import numpy as np
import pytest
from PIL import Image

from rosbridge_app.collector import conversions as conv


def stamp(sec=100, nanosec=0):
    return NS(sec=sec, nanosec=nanosec)


def fix(lat=50.6, lon=7.1, status=0, alt=100.0, cov=(0.04, 0, 0, 0, 0.09, 0, 0, 0, 1), ctype=2):
    return NS(
        header=NS(stamp=stamp()),
        status=NS(status=status),
        latitude=lat,
        longitude=lon,
        altitude=alt,
        position_covariance=list(cov),
        position_covariance_type=ctype,
    )


def test_fix_keeps_position_altitude_and_accuracy():
    f = conv.navsat_fix(fix())
    assert (f["lon"], f["lat"], f["alt"], f["status"]) == (7.1, 50.6, 100.0, 0)
    assert f["accuracy"] == pytest.approx(0.3)
    assert f["robot_stamp"].timestamp() == 100


@pytest.mark.parametrize(
    "bad",
    [
        {"status": -1},
        {"status": -3},
        {"lat": float("nan")},
        {"lon": float("inf")},
        {"lat": 91.0},
    ],
)
def test_unusable_fixes_are_dropped(bad):
    assert conv.navsat_fix(fix(**bad)) is None


def test_a_fix_whose_driver_leaves_the_status_unset_is_kept():
    # NavSatFix() in Jazzy says STATUS_UNKNOWN (-2) until the driver sets it.
    f = conv.navsat_fix(fix(status=-2))
    assert (f["lon"], f["lat"], f["status"]) == (7.1, 50.6, 0)


def test_fix_with_nan_altitude_keeps_the_position():
    assert conv.navsat_fix(fix(alt=float("nan")))["alt"] is None


def grid(width, height, data, yaw=0.0, ox=-1.0, oy=-2.0, res=0.05):
    o = NS(
        position=NS(x=ox, y=oy, z=0.0),
        orientation=NS(x=0.0, y=0.0, z=math.sin(yaw / 2), w=math.cos(yaw / 2)),
    )
    return NS(
        header=NS(stamp=stamp(), frame_id="map"),
        info=NS(width=width, height=height, resolution=res, origin=o),
        data=data,
    )


def test_grid_becomes_png_with_origin_at_the_bottom_left():
    # Cell (row 0, col 0) is at the origin, i.e. the image's bottom-left pixel.
    cells = [100, 0, 0, -1, -1, -1]  # 3 wide, 2 high
    msg = grid(3, 2, cells, yaw=0.5)
    img = Image.open(io.BytesIO(conv.grid_to_png(msg)))
    assert img.size == (3, 2)
    px = np.asarray(img)
    assert px[1, 0] == 0  # occupied: black, bottom-left
    assert px[1, 1] == 254  # free: white
    assert px[0, 0] == 205  # unknown: grey, top row
    geometry = conv.grid_geometry(msg)
    assert geometry["origin_yaw"] == pytest.approx(0.5)
    assert (geometry["origin_x"], geometry["origin_y"], geometry["resolution"]) == (-1, -2, 0.05)


def test_empty_or_inconsistent_grid_is_not_usable():
    assert not conv.grid_is_usable(grid(0, 0, []))
    assert not conv.grid_is_usable(grid(3, 2, [0, 0]))


def image(encoding, pixels: np.ndarray, step_pad=0, bigendian=False):
    h, w = pixels.shape[:2]
    rows = pixels.reshape(h, -1).view(np.uint8)
    if step_pad:
        rows = np.hstack([rows, np.zeros((h, step_pad), np.uint8)])
    return NS(
        header=NS(stamp=stamp()),
        encoding=encoding,
        width=w,
        height=h,
        step=rows.shape[1],
        is_bigendian=bigendian,
        data=rows.tobytes(),
    )


def decoded(jpeg: bytes) -> np.ndarray:
    return np.asarray(Image.open(io.BytesIO(jpeg)).convert("RGB")).astype(int)


@pytest.mark.parametrize(
    "encoding,order",
    [("rgb8", [0, 1, 2]), ("bgr8", [2, 1, 0]), ("rgba8", [0, 1, 2, 3]), ("bgra8", [2, 1, 0, 3])],
)
def test_colour_images_keep_their_colours(encoding, order):
    red = np.zeros((16, 16, len(order)), np.uint8)
    red[..., 0] = 220  # in RGB(A) order
    if len(order) == 4:
        red[..., 3] = 255
    pixels = red[..., order]
    out = decoded(conv.image_to_jpeg(image(encoding, pixels, step_pad=4)))
    r, g, b = out[8, 8]
    assert r > 180 and g < 40 and b < 40


@pytest.mark.parametrize("pattern", ["rggb", "bggr", "gbrg", "grbg"])
def test_bayer_mosaics_keep_their_colours(pattern):
    # A scene of one orange colour, sampled through the named 2x2 filter.
    colour = {"r": 230, "g": 120, "b": 10}
    cell = np.array([[colour[c] for c in pattern[:2]], [colour[c] for c in pattern[2:]]])
    mosaic = np.tile(cell, (8, 8)).astype(np.uint8)
    out = decoded(conv.image_to_jpeg(image(f"bayer_{pattern}8", mosaic[..., None])))
    r, g, b = out[8, 8]
    assert abs(r - 230) < 25 and abs(g - 120) < 25 and abs(b - 10) < 25, (r, g, b)


@pytest.mark.parametrize("encoding", ["uyvy", "yuv422", "yuyv"])
def test_yuv422_keeps_its_colours(encoding):
    # BT.601 red: Y 82, U (Cb) 90, V (Cr) 240, two pixels in four bytes.
    y, u, v = 82, 90, 240
    pair = [y, u, y, v] if encoding == "yuyv" else [u, y, v, y]
    rows = np.tile(np.array(pair, np.uint8), (8, 8))  # 8 rows of 16 pixels
    msg = image(encoding, rows)
    msg.width = 16
    r, g, b = decoded(conv.image_to_jpeg(msg))[4, 8]
    assert r > 200 and g < 60 and b < 60, (r, g, b)


@pytest.mark.parametrize("encoding,dtype", [("32FC1", np.float32), ("16UC1", np.uint16)])
def test_depth_images_are_stretched_and_invalid_depths_are_black(encoding, dtype):
    depth = np.array([[0.5, 2.0], [1.25, 2.0]], dtype=np.float64)
    depth = (depth * 1000).astype(dtype) if dtype == np.uint16 else depth.astype(dtype)
    if dtype == np.float32:
        depth[1, 1] = np.nan
    pixels, mode = conv.image_array(image(encoding, depth))
    assert mode == "L"
    assert pixels[0, 0] == 0 and pixels[0, 1] == 255
    assert pixels[1, 0] == pytest.approx(127, abs=1)
    if dtype == np.float32:
        assert pixels[1, 1] == 0


def test_mono8_is_kept_as_grey():
    grey = np.array([[0, 100], [200, 255]], np.uint8)
    pixels, mode = conv.image_array(image("mono8", grey))
    assert mode == "L" and pixels.tolist() == grey.tolist()


def test_mono16_is_stretched_to_visible_grey():
    depth = np.array([[1000, 3000], [2000, 3000]], dtype=np.uint16)
    out = decoded(conv.image_to_jpeg(image("mono16", depth)))
    assert out[0, 0, 0] < out[1, 0, 0] < out[0, 1, 0]


def test_unknown_encoding_and_short_data_raise():
    with pytest.raises(conv.UnsupportedImage):
        conv.image_to_jpeg(
            NS(encoding="weird", width=2, height=2, step=2, is_bigendian=False, data=b"0000")
        )
    with pytest.raises(conv.UnsupportedImage):
        conv.image_to_jpeg(
            NS(encoding="rgb8", width=4, height=4, step=12, is_bigendian=False, data=b"\0" * 10)
        )


def test_large_frames_are_scaled_down():
    big = np.zeros((2160, 3840, 3), np.uint8)
    out = Image.open(io.BytesIO(conv.image_to_jpeg(image("rgb8", big), max_side=1920)))
    assert out.size == (1920, 1080)


def test_compressed_images_must_decode():
    buf = io.BytesIO()
    Image.new("RGB", (4, 4)).save(buf, format="PNG")
    assert conv.compressed_image(NS(format="png", data=buf.getvalue()))[1] == "png"
    with pytest.raises(conv.UnsupportedImage):
        conv.compressed_image(NS(format="jpeg", data=b"\xff\xd8garbage"))
