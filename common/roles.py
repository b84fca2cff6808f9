"""The roles, as Django groups (made by migrations events.0002 and 0007, and
given the rights of models added since by events.0024).

The people's roles are ordered, each including the ones below it: an
administrator may do everything an operator may, an operator everything a
viewer may.  ``robot`` stands apart: a robot account is bound to vehicles
(``events.RobotAccount``) and writes what its robot records into their legs
only (``events.rules.check_robot_target``).  It holds none of the people's
roles, even when its account is also in their groups: a token lost with a
robot must not carry an operator's rights.
"""

VIEWER = "viewer"
OPERATOR = "operator"
ADMINISTRATOR = "administrator"
ORDER = (VIEWER, OPERATOR, ADMINISTRATOR)
ROBOT = "robot"

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

# The apps whose rows the roles cover in Django admin: viewers may look at them,
# administrators write them all (test plans, judgements, basemaps, finalising
# included).  Libraries' own records stay the superuser's (ftt_site.admin_site).
ROLE_APPS = ("events", "telemetry", "basemaps")

# What a robot account writes besides, into legs of its own vehicles only:
# segments by reporting its mode, and its telemetry.  The API views name the
# actions that write them (``robot_actions``); the seeded robot group gets
# these models' add permission.
ROBOT_WRITES = (
    "events.segment",
    "telemetry.pose",
    "telemetry.localpose",
    "telemetry.mapimage",
    "telemetry.image",
    "telemetry.recording",
)


def write_role(model) -> str:
    """The role needed to write rows of ``model`` (a model class or its label)."""
    label = model if isinstance(model, str) else model._meta.label_lower
    return WRITERS.get(label, ADMINISTRATOR)


def written_by(role: str) -> list[str]:
    """Labels of the models a role may write, its own and those of lower roles."""
    return [label for label, writer in WRITERS.items() if ORDER.index(writer) <= ORDER.index(role)]


def _active(user) -> bool:
    return bool(user) and user.is_authenticated and user.is_active


def remember_groups(user, names) -> None:
    """The user's group names, read along with the login (common.api.authentication)."""
    user._ftt_groups = frozenset(names)


def _group_names(user) -> frozenset[str]:
    # One query per request: the user object lives as long as the request.
    cached = getattr(user, "_ftt_groups", None)
    if cached is None:
        cached = frozenset(user.groups.values_list("name", flat=True))
        user._ftt_groups = cached
    return cached


def is_robot(user) -> bool:
    """A robot account: in the robot group (a superuser never is one)."""
    return _active(user) and not user.is_superuser and ROBOT in _group_names(user)


def user_role_rank(user) -> int:
    """-1 for no role (robot accounts too), else the index of the highest role in ORDER."""
    if not _active(user):
        return -1
    if user.is_superuser:
        return len(ORDER) - 1
    names = _group_names(user)
    if ROBOT in names:
        return -1
    return max((i for i, role in enumerate(ORDER) if role in names), default=-1)


def has_role(user, role: str) -> bool:
    return user_role_rank(user) >= ORDER.index(role)


def may_write(user, model) -> bool:
    return has_role(user, write_role(model))
