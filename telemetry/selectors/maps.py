from events.models import Shift
from telemetry.models import MapImage


def current_map(shift: Shift) -> MapImage | None:
    """The newest map of a shift is the one the GUI and the report show."""
    return shift.maps.order_by("-received", "-id").first()


__all__ = ["MapImage", "current_map"]
