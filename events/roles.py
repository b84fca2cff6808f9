"""The three roles, as Django groups (created by migration events.0002).

Each role includes the ones below it: an administrator may do everything an
operator may, an operator everything a viewer may.
"""

VIEWER = "viewer"
OPERATOR = "operator"
ADMINISTRATOR = "administrator"
ORDER = (VIEWER, OPERATOR, ADMINISTRATOR)


def user_role_rank(user) -> int:
    """-1 for no role, else the index of the highest role in ORDER."""
    if not user or not user.is_authenticated or not user.is_active:
        return -1
    if user.is_superuser:
        return len(ORDER) - 1
    cached = getattr(user, "_ftt_role_rank", None)
    if cached is None:
        names = set(user.groups.values_list("name", flat=True))
        cached = max((i for i, role in enumerate(ORDER) if role in names), default=-1)
        user._ftt_role_rank = cached
    return cached


def has_role(user, role: str) -> bool:
    return user_role_rank(user) >= ORDER.index(role)
