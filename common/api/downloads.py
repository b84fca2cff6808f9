"""Downloads whose size grows with the data (a test event's exports, a search's
found segments): sent piece by piece as they are made, so that a server's
memory holds a few pieces, never the whole file.

The pieces read the database.  Under ASGI (the production server) Django would
first collect a plain iterator into one list; here they are made a batch at a
time on the request's own thread (``sync_to_async``, thread-sensitive: the one
with its database connection), and a client that goes away stops them.  Under
WSGI (the test client, ``runserver``) they are iterated as they are.
"""

import itertools
from collections.abc import AsyncIterator, Iterable, Iterator

from asgiref.sync import sync_to_async
from django.core.handlers.asgi import ASGIRequest
from django.http import StreamingHttpResponse

# Pieces (CSV lines, GeoJSON features, GPX tracks) made per trip to the request's thread.
PIECES_PER_BATCH = 500


def streamed_download(
    request, pieces: Iterable[str], content_type: str, filename: str
) -> StreamingHttpResponse:
    """An attachment ``filename`` whose body is ``pieces`` joined, sent as they come."""
    django_request = getattr(request, "_request", request)  # DRF's Request wraps Django's
    if isinstance(django_request, ASGIRequest):
        content = _batches(iter(pieces))
    else:
        content = _encoded(pieces)
    response = StreamingHttpResponse(content, content_type=content_type)
    response["Content-Disposition"] = f'attachment; filename="{filename}"'
    return response


def _encoded(pieces: Iterable[str]) -> Iterator[bytes]:
    for piece in pieces:
        yield piece.encode()


async def _batches(pieces: Iterator[str]) -> AsyncIterator[bytes]:
    take = sync_to_async(lambda: list(itertools.islice(pieces, PIECES_PER_BATCH)))
    while batch := await take():
        yield "".join(batch).encode()
