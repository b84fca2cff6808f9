from rest_framework.permissions import SAFE_METHODS, BasePermission

from events import roles


class RolePermission(BasePermission):
    """Viewers read; views name the role needed to write (``write_role``)."""

    message = "Your account does not have the role needed for this."

    def has_permission(self, request, view):
        if request.method in SAFE_METHODS:
            return roles.has_role(request.user, getattr(view, "read_role", roles.VIEWER))
        return roles.has_role(request.user, getattr(view, "write_role", roles.OPERATOR))
