"""The three roles, as Django groups (created by migration events.0002).

Each role includes the ones below it: an administrator may do everything an
operator may, an operator everything a viewer may.
"""

VIEWER = "viewer"
OPERATOR = "operator"
ADMINISTRATOR = "administrator"
ORDER = (VIEWER, OPERATOR, ADMINISTRATOR)

# Who may write what: the lowest role that may add, change and delete rows of
# each model ("app_label.modelname").  Every role reads everything.  The API's
# permission class, Django admin and the seeded groups all read this table;
# a model missing here is written by administrators only.
WRITERS = {
    # What an operator logs during a test.
    "events.testevent": OPERATOR,
    "events.shift": OPERATOR,
    "events.leg": OPERATOR,
    "events.segment": OPERATOR,
    "events.note": OPERATOR,
    "telemetry.image": OPERATOR,
    "telemetry.pose": OPERATOR,
    "telemetry.localpose": OPERATOR,
    "telemetry.mapimage": OPERATOR,
    "telemetry.recording": OPERATOR,
    # Configuration and catalogues.
    "events.personnel": ADMINISTRATOR,
    "events.performer": ADMINISTRATOR,
    "events.vehicle": ADMINISTRATOR,
    "events.posesource": ADMINISTRATOR,
    "events.weather": ADMINISTRATOR,
    "events.itoreason": ADMINISTRATOR,
    "events.segmenttype": ADMINISTRATOR,
}


def write_role(model) -> str:
    """The role needed to write rows of ``model`` (a model class or its label)."""
    label = model if isinstance(model, str) else model._meta.label_lower
    return WRITERS.get(label, ADMINISTRATOR)


def written_by(role: str) -> list[str]:
    """Labels of the models a role may write, its own and those of lower roles."""
    return [label for label, writer in WRITERS.items() if ORDER.index(writer) <= ORDER.index(role)]


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


def may_write(user, model) -> bool:
    return has_role(user, write_role(model))
