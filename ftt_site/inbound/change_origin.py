"""Names the channel and the request of each web request for the change history
(events.history); the request's user is read when a row is saved, so a DRF
token login, made inside the view, counts too."""

from asgiref.sync import iscoroutinefunction
from django.utils.decorators import sync_and_async_middleware

from events.history import authored

# An amendment of a final test event names its reason in this header (API, GUI);
# admin's change forms have a field for it (events.admin.shared.HistoryAdmin).
REASON_HEADER = "X-FTT-Change-Reason"


def reason_of(request) -> str:
    return request.headers.get(REASON_HEADER, "").strip()


# The channel is the route taken, never a header the client chose: the REST API,
# the original robots' API and admin by their prefixes, the pages' own calls
# (/gui/api/, forms) the GUI; a REST API call made with the pages' session is
# the GUI's too (events.history, once DRF has signed the request in).
_ROUTES = (("/api/", "api"), ("/legacy/", "legacy"), ("/admin/", "admin"))


def channel_of(request) -> str:
    for prefix, channel in _ROUTES:
        if request.path.startswith(prefix):
            return channel
    return "gui"


@sync_and_async_middleware
def ChangeOriginMiddleware(get_response):  # noqa: N802  (Django middleware naming)
    if iscoroutinefunction(get_response):

        async def middleware(request):
            with authored(channel_of(request), request=request, reason=reason_of(request)):
                return await get_response(request)

    else:

        def middleware(request):
            with authored(channel_of(request), request=request, reason=reason_of(request)):
                return get_response(request)

    return middleware
