"""Proof that a list endpoint does not run one query per row (no N+1)."""

from django.db import connection
from django.test.utils import CaptureQueriesContext

from events import roles

# Token + user, the user's groups (role check), the page count, the page itself.
LIST_QUERIES = 4


def assert_constant_queries(api_client, django_assert_max_num_queries, url, add_rows, *, most):
    """Queries for ``url`` after 2 rows and after 25 more must match and stay within ``most``."""
    client = api_client(roles.VIEWER)
    add_rows(2)
    with CaptureQueriesContext(connection) as few:
        first = client.get(url)
    assert first.status_code == 200, first.content
    add_rows(25)
    with django_assert_max_num_queries(most):
        many = client.get(url)
    assert many.status_code == 200
    assert len(many.content) > len(first.content), "the extra rows must show up"
    with CaptureQueriesContext(connection) as again:
        client.get(url)
    assert len(again) == len(few), [q["sql"] for q in again.captured_queries]
