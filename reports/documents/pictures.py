"""Pictures placed in a report: camera frames as JPEG files (a thumbnail and a
full-size copy, each distinct picture encoded once) and a shift's map image as
the background of its local-frame maps."""

import hashlib
import io
from pathlib import Path

import numpy as np
from django.utils.translation import gettext as _
from django.utils.translation import gettext_noop
from PIL import Image as PILImage

from reports.charts.maps import Background
from telemetry.models import Image
from telemetry.selectors.maps import current_map

THUMBNAIL_PX = 480
FULL_IMAGE_PX = 1600


class Pictures:
    """Writes picture files into ``root``; what it cannot read it leaves out and
    adds to ``warnings``.  ``full_size``: also a full-size copy of each frame."""

    def __init__(self, root: Path, full_size: bool, warnings: list[str], time_stage):
        self.root = root
        self.full_size = full_size
        self.warnings = warnings
        self.time_stage = time_stage
        self.encoded: dict[str, tuple[str, str] | None] = {}  # content hash: (thumb, full)
        self.backgrounds: dict[int, Background | None] = {}  # by shift id

    def camera(self, image: Image) -> tuple[str, str] | None:
        """(thumbnail, full-size) file names; each distinct picture is decoded once."""
        try:
            with image.image.open("rb") as fh:
                content = fh.read()
        except OSError as exc:
            self.warnings.append(_unreadable(image.pk, exc))
            return None
        digest = hashlib.sha256(content).hexdigest()[:20]
        if digest not in self.encoded:
            with self.time_stage(gettext_noop("image encoding")):
                self.encoded[digest] = self._encode(image.pk, content, digest)
        return self.encoded[digest]

    def _encode(self, pk: int, content: bytes, digest: str) -> tuple[str, str] | None:
        try:
            picture = PILImage.open(io.BytesIO(content))
            picture.draft("RGB", (FULL_IMAGE_PX, FULL_IMAGE_PX))
            picture = picture.convert("RGB")
        except (OSError, ValueError) as exc:
            self.warnings.append(_unreadable(pk, exc))
            return None
        names = []
        sizes = [("thumb", THUMBNAIL_PX)]
        if self.full_size:
            sizes.append(("full", FULL_IMAGE_PX))
        for kind, size in sizes:
            copy = picture.copy()
            copy.thumbnail((size, size))
            name = f"img-{digest}-{kind}.jpg"
            copy.save(self.root / name, "JPEG", quality=82)
            names.append(name)
        return names[0], names[-1]

    def background(self, shift) -> Background | None:
        """The shift's current map image in grey, placed in its frame; None without one."""
        if shift.id not in self.backgrounds:
            map_image = current_map(shift)
            background = None
            if map_image is not None:
                try:
                    with map_image.image.open("rb") as fh:
                        array = np.asarray(PILImage.open(fh).convert("L"))
                    background = Background(
                        array,
                        map_image.resolution,
                        map_image.origin_x,
                        map_image.origin_y,
                        map_image.origin_yaw,
                    )
                except (OSError, ValueError) as exc:
                    self.warnings.append(
                        _("%(shift)s: map image unreadable (%(reason)s).")
                        % {"shift": shift, "reason": exc}
                    )
            self.backgrounds[shift.id] = background
        return self.backgrounds[shift.id]


def _unreadable(pk: int, reason: Exception) -> str:
    return _("Image %(id)s unreadable (%(reason)s); left out.") % {"id": pk, "reason": reason}
