"""POST /api/token/: username and password for a token, counted by django-axes like
every other login path."""

from rest_framework.authtoken.serializers import AuthTokenSerializer
from rest_framework.authtoken.views import ObtainAuthToken


class LoginSerializer(AuthTokenSerializer):
    def validate(self, attrs):
        # django-axes marks a lockout on Django's request, which its middleware
        # reads; DRF's wrapper would keep the mark to itself.
        request = self.context.get("request")
        self.context["request"] = getattr(request, "_request", request)
        return super().validate(attrs)


class ObtainToken(ObtainAuthToken):
    serializer_class = LoginSerializer


obtain_token = ObtainToken.as_view()
