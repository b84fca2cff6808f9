"""What a robot account is bound to."""

from django.conf import settings

from common.memo import Expiring
from events.models import Vehicle

# user id -> {vehicle id: key}, across the requests of a robot that posts many
# times a second.  Binding changes through this process clear it at once
# (events.apps); through another process they count within these seconds.
_bindings = Expiring(settings.FTT_TOKEN_CACHE_SECONDS)


def robot_vehicles(user) -> dict[int, str]:
    """``{vehicle id: key}`` of the vehicles ``user``'s robot account logs for."""
    cached = _bindings.get(user.pk)
    if cached is None:
        rows = Vehicle.objects.filter(robot_accounts__user=user).values_list("pk", "key")
        cached = dict(rows)
        _bindings.put(user.pk, cached)
    return cached


def forget_bindings(*args, **kwargs) -> None:
    _bindings.clear()
