from rest_framework.permissions import SAFE_METHODS, BasePermission

from common import roles

ROBOT_REFUSED = (
    "A robot account only reports the mode and telemetry of its own vehicles and reads "
    "what it logs with; it may not do this."
)


class RolePermission(BasePermission):
    """Viewers read (also the actions a view names in ``read_actions``, sent by
    POST).  Writing needs the role :data:`common.roles.WRITERS` names for the
    view's model; views without a model name it (``write_role``).

    A robot account may run only the actions a view names in ``robot_actions``;
    which vehicle's rows it touches is checked by the view (events.api.permissions).
    """

    message = "Your account does not have the role needed for this."

    def has_permission(self, request, view):
        if roles.is_robot(request.user):
            self.message = ROBOT_REFUSED
            return getattr(view, "action", None) in getattr(view, "robot_actions", ())
        # A view names in ``read_actions`` what only reads though sent by POST (a search).
        reads = getattr(view, "action", None) in getattr(view, "read_actions", ())
        if request.method in SAFE_METHODS or reads:
            return roles.has_role(request.user, getattr(view, "read_role", roles.VIEWER))
        role = getattr(view, "write_role", None)
        if role is None:
            queryset = getattr(view, "queryset", None)
            role = roles.write_role(queryset.model) if queryset is not None else roles.OPERATOR
        return roles.has_role(request.user, role)
