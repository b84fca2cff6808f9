"""Which vehicle's rows a robot account reaches; the rule is events.rules.check_robot_target."""

from rest_framework.permissions import BasePermission

from events import rules


class RobotTargetPermission(BasePermission):
    """Rows addressed in the URL (``legs/{id}/mode/``); rows named in a request body
    are checked by :class:`events.api.serializers.PrimaryKeyField`."""

    def has_object_permission(self, request, view, obj):
        rules.check_robot_target(request.user, obj)
        return True
