import faulthandler
import os
import signal

from django.core.asgi import get_asgi_application

# `kill -USR1 <pid>` prints every thread's stack to stderr: the way to see
# where a server that stopped answering is stuck, without stopping it.
if hasattr(signal, "SIGUSR1"):
    faulthandler.register(signal.SIGUSR1, all_threads=True)

os.environ.setdefault("DJANGO_SETTINGS_MODULE", "ftt_site.settings")
django_asgi_app = get_asgi_application()

from channels.auth import AuthMiddlewareStack  # noqa: E402
from channels.routing import ProtocolTypeRouter, URLRouter  # noqa: E402
from channels.security.websocket import AllowedHostsOriginValidator  # noqa: E402

from ftt_site.inbound.limits import RequestLimits  # noqa: E402
from ftt_site.inbound.pose_route import PoseRoute  # noqa: E402
from ftt_site.server.loop_watch import lifespan  # noqa: E402
from ftt_site.server.warmup import warm_up  # noqa: E402
from live.routing import websocket_urlpatterns  # noqa: E402

warm_up()

application = ProtocolTypeRouter(
    {
        "http": RequestLimits(PoseRoute(django_asgi_app)),
        "websocket": AllowedHostsOriginValidator(
            AuthMiddlewareStack(URLRouter(websocket_urlpatterns))
        ),
        "lifespan": lifespan,
    }
)
