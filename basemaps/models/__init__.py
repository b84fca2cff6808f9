from basemaps.models.layers import BasemapLayer, EventBasemap

__all__ = ["BasemapLayer", "EventBasemap"]
