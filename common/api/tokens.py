"""POST /api/token/: username and password for a token, counted by django-axes like
every other login path."""

from axes.helpers import get_lockout_response
from rest_framework.authtoken.views import ObtainAuthToken
from rest_framework.exceptions import ValidationError


class ObtainToken(ObtainAuthToken):
    def post(self, request, *args, **kwargs):
        try:
            return super().post(request, *args, **kwargs)
        except ValidationError:
            # django-axes marks a lockout on the request it was handed, DRF's here,
            # where its middleware never looks: answer it as every login path does.
            if getattr(request, "axes_locked_out", False):
                username = request.data.get("username") if hasattr(request.data, "get") else None
                return get_lockout_response(request, credentials={"username": username})
            raise


obtain_token = ObtainToken.as_view()
