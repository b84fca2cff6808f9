"""What a robot account is bound to."""

from events.models import Vehicle


def robot_vehicles(user) -> dict[int, str]:
    """``{vehicle id: key}`` of the vehicles ``user``'s robot account logs for.

    Kept on the user object, which lives as long as its request: however many
    rows a request checks, this is one query.
    """
    cached = getattr(user, "_ftt_robot_vehicles", None)
    if cached is None:
        rows = Vehicle.objects.filter(robot_accounts__user=user).values_list("pk", "key")
        cached = dict(rows)
        user._ftt_robot_vehicles = cached
    return cached
