"""Adding basemap layers and choosing a test event's default one."""

import tempfile
from pathlib import Path

from django.conf import settings
from django.core.exceptions import ValidationError
from django.core.files import File
from django.db import transaction
from django.utils.text import slugify
from django.utils.translation import gettext as _

from basemaps.files import inspect_file, local_file
from basemaps.models import BasemapLayer, EventBasemap


def max_upload_bytes() -> int:
    return int(settings.FTT_BASEMAP_MAX_UPLOAD_MB) * 1024 * 1024


def check_size(size: int) -> None:
    limit = max_upload_bytes()
    if size > limit:
        raise ValidationError(
            (
                _(
                    "The file has %(size)s MB; basemaps may have at most %(limit)s MB "
                    "(FTT_BASEMAP_MAX_UPLOAD_MB)."
                )
                % {"size": f"{size / 2**20:.0f}", "limit": f"{limit / 2**20:.0f}"}
            ),
            code="too_large",
        )


def _unique_key(name: str) -> str:
    base = slugify(name)[:50] or "layer"
    key, n = base, 1
    while BasemapLayer.objects.filter(key=key).exists():
        n += 1
        key = f"{base}-{n}"
    return key


def apply_file_facts(layer: BasemapLayer, path) -> None:
    """Fill kind, bounds, zooms and tile format from the file; refuse a bad file."""
    facts = inspect_file(path)
    layer.kind = facts.kind
    layer.west, layer.south, layer.east, layer.north = facts.bounds
    layer.min_zoom, layer.max_zoom = facts.min_zoom, facts.max_zoom
    layer.tile_format = facts.tile_format
    layer.url = ""


def register_file(path, *, name: str = "", attribution: str = "", key: str = "") -> BasemapLayer:
    """A layer from a file on disk (``ftt_basemap import``, fetched archives).

    The file is checked before anything is written and copied into MEDIA_ROOT.
    """
    path = local_file(path)
    check_size(path.stat().st_size)
    layer = BasemapLayer(name=name or path.stem, attribution=attribution)
    apply_file_facts(layer, path)
    with transaction.atomic():
        layer.key = key or _unique_key(layer.name)
        layer.full_clean(exclude=["file"])
        with path.open("rb") as f:
            # FieldFile.save stores the file and saves the row in this transaction;
            # if the row fails, django-cleanup is not involved, so remove it here.
            try:
                layer.file.save(path.name, File(f), save=True)
            except Exception:
                if layer.file:
                    layer.file.storage.delete(layer.file.name)
                raise
    return layer


def register_url(
    url: str, *, name: str, attribution: str = "", max_zoom: int = 19, key="", enabled=True
):
    """An external layer; the address must name an allowed tile server (basemaps.hosts)."""
    layer = BasemapLayer(
        name=name,
        kind=BasemapLayer.URL,
        url=url,
        attribution=attribution,
        max_zoom=max_zoom,
        enabled=enabled,
    )
    with transaction.atomic():
        layer.key = key or _unique_key(name)
        layer.full_clean()
        layer.save()
    return layer


@transaction.atomic
def set_event_default(test_event, layer: BasemapLayer | None) -> None:
    if layer is None:
        EventBasemap.objects.filter(test_event=test_event).delete()
        return
    EventBasemap.objects.update_or_create(test_event=test_event, defaults={"layer": layer})


def check_upload(layer: BasemapLayer, upload) -> None:
    """Validate an uploaded file and fill the layer's facts from it, before it is stored.

    Django keeps uploads above FILE_UPLOAD_MAX_MEMORY_SIZE in a temporary file;
    smaller ones are written to one here, since the readers need a path.
    """
    check_size(upload.size)
    if hasattr(upload, "temporary_file_path"):
        apply_file_facts(layer, upload.temporary_file_path())
        return
    with tempfile.NamedTemporaryFile(suffix=Path(upload.name).suffix) as copy:
        for chunk in upload.chunks():
            copy.write(chunk)
        copy.flush()
        apply_file_facts(layer, copy.name)
    upload.seek(0)
