"""Base view sets: DRF handles reading, the service layer does every write."""

from rest_framework import mixins, status, viewsets
from rest_framework.response import Response

from common import roles
from common.api.permissions import RolePermission
from common.retries import is_retry
from events.api.permissions import RobotTargetPermission
from events.services import deletion


class ServiceBaseViewSet(
    mixins.ListModelMixin,
    mixins.RetrieveModelMixin,
    mixins.DestroyModelMixin,
    viewsets.GenericViewSet,
):
    """List, retrieve and delete; deletion goes through :meth:`delete_with_service`."""

    # The role to write comes from common.roles.WRITERS for the queryset's model.
    read_role = roles.VIEWER
    permission_classes = [RolePermission, RobotTargetPermission]
    # What a robot account may call here (common.roles.ROBOT); none by default.
    robot_actions: tuple[str, ...] = ()

    def delete_with_service(self, instance) -> None:
        deletion.delete(instance)

    def perform_destroy(self, instance):
        self.delete_with_service(instance)

    def payload(self, serializer_class):
        """A request body checked by ``serializer_class``, with the request at hand, so
        that the rows it names are checked against a robot's vehicles."""
        serializer = serializer_class(data=self.request.data, context=self.get_serializer_context())
        serializer.is_valid(raise_exception=True)
        return serializer

    def respond(self, instance, serializer_class=None, code=status.HTTP_200_OK):
        serializer_class = serializer_class or self.get_serializer_class()
        context = self.get_serializer_context()
        return Response(serializer_class(instance, context=context).data, status=code)


class ServiceCreateMixin:
    """Create through :meth:`create_with_service`; a new row answers 201.

    A create that carries a ``uid`` already stored (a retry after a lost answer)
    answers 200 with the stored row; the service decides whether it is a retry
    or another owner's uid (409), by common.retries.
    """

    def create_with_service(self, data: dict):
        raise NotImplementedError

    def create(self, request, *args, **kwargs):
        serializer = self.get_serializer(data=request.data)
        serializer.is_valid(raise_exception=True)
        row = self.create_with_service(dict(serializer.validated_data))
        code = status.HTTP_200_OK if is_retry(row) else status.HTTP_201_CREATED
        return self.respond(row, code=code)


class ServiceUpdateMixin:
    """PUT / PATCH through :meth:`update_with_service`."""

    def update_with_service(self, instance, data: dict):
        raise NotImplementedError

    def update(self, request, *args, **kwargs):
        partial = kwargs.pop("partial", False)
        instance = self.get_object()
        serializer = self.get_serializer(instance, data=request.data, partial=partial)
        serializer.is_valid(raise_exception=True)
        instance = self.update_with_service(instance, dict(serializer.validated_data))
        return self.respond(instance)

    def partial_update(self, request, *args, **kwargs):
        kwargs["partial"] = True
        return self.update(request, *args, **kwargs)


class ServiceViewSet(ServiceCreateMixin, ServiceUpdateMixin, ServiceBaseViewSet):
    """Full CRUD, every write through a service function."""
