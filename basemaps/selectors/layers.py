"""Which layers there are and which one a test event starts on."""

from collections import Counter

from django.urls import reverse
from django.utils.html import escape

from basemaps.models import BasemapLayer, EventBasemap


def default_layer(test_events) -> BasemapLayer | None:
    """The layer a test event (an id) or several (ids) start on; where several
    differ (a fleet logging into several events), the one most of them start on."""
    ids = [test_events] if isinstance(test_events, int) else list(test_events)
    found = Counter(
        EventBasemap.objects.filter(test_event_id__in=ids, layer__enabled=True)
        .order_by("test_event_id")
        .values_list("layer_id", flat=True)
    ).most_common(1)
    return BasemapLayer.objects.get(pk=found[0][0]) if found else None


def tile_url_template(layer: BasemapLayer, fmt: str = "png") -> str:
    if not layer.served_by_ftt:
        return layer.url
    base = reverse("basemap-tile", kwargs={"key": layer.key, "z": 0, "x": 0, "y": 0, "fmt": fmt})
    return base.replace("/0/0/0.", "/{z}/{x}/{y}.")


def layer_list(test_event_ids=()) -> list[dict]:
    """What the GUI's layer switcher offers; the test events' default is marked."""
    default = default_layer(test_event_ids) if test_event_ids else None
    return [
        {
            "key": layer.key,
            "name": layer.name,
            "url": tile_url_template(layer),
            # Leaflet puts attributions in the page as HTML; the layer's is text.
            "attribution": escape(layer.attribution),
            "minZoom": layer.min_zoom,
            "maxZoom": layer.max_zoom,
            # Leaflet wants [[south, west], [north, east]].
            "bounds": [[layer.south, layer.west], [layer.north, layer.east]]
            if layer.bounds
            else None,
            "default": default is not None and layer.pk == default.pk,
        }
        for layer in BasemapLayer.objects.filter(enabled=True)
    ]
