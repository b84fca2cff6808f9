"""Names the channel and the request of each web request for the change history
(events.history); the request's user is read when a row is saved, so a DRF
token login, made inside the view, counts too."""

from asgiref.sync import iscoroutinefunction
from django.utils.decorators import sync_and_async_middleware

from events.history import authored

# An amendment of a final test event names its reason in this header (API, GUI);
# admin's change forms have a field for it (events.admin.HistoryAdmin).
REASON_HEADER = "X-FTT-Change-Reason"


def reason_of(request) -> str:
    return request.headers.get(REASON_HEADER, "").strip()


def channel_of(request) -> str:
    """admin; api for a client with a token; gui for the pages' own (session) calls."""
    if request.path.startswith("/admin/"):
        return "admin"
    if "Authorization" in request.headers:
        return "api"
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
