"""A retried write: a client that lost the answer sends the same uid again.

Every row a client may create carries the uid it chose, and a uid already
stored answers with the row stored first (the API with 200, not 201) instead
of storing it twice.  A uid is only a retry when it names a row of the same
owner (segment, shift, leg, vehicle) as the request: a uid of another owner's
row (another note, another vehicle's pose, a guessed or reused uid) is refused
(HTTP 409) without that row, and nothing is written.

The services that create rows call this module, each naming its owner; the
API views only tell a retry (:func:`is_retry`) from a new row by the answer.
"""

from django.db.models import BooleanField, ExpressionWrapper, Q
from django.utils.translation import gettext, gettext_noop

from common.errors import RuleViolation

ANOTHER_OWNER = gettext_noop("This uid belongs to another row; send a new one.")


class AnotherOwner(RuleViolation):
    """A uid sent for a row that is stored under another owner (``uid``)."""

    def __init__(self, uid):
        super().__init__({"uid": [gettext(ANOTHER_OWNER)]})
        self.uid = uid


def _owned(model, uids, owner):
    if not owner:
        raise TypeError("a retry is known by its uid and its owner; name the owner")
    same = ExpressionWrapper(Q(**owner), output_field=BooleanField())
    return model.objects.filter(uid__in=uids).annotate(retry_same_owner=same)


def _check(uid, same_owner) -> None:
    if not same_owner:
        raise AnotherOwner(uid)


def stored_rows(model, uids, **owner) -> dict:
    """{uid: row stored under it} for those of ``uids`` already stored.  ``owner``
    gives the lookups a retry must match (``segment_id=...``, also across
    relations: ``segment__leg__shift__vehicle=...``); a stored row that does
    not match is refused with :class:`AnotherOwner` (HTTP 409), without the row."""
    uids = [uid for uid in uids if uid is not None]
    if not uids:
        return {}
    rows = {row.uid: row for row in _owned(model, uids, owner)}
    for row in rows.values():
        _check(row.uid, row.retry_same_owner)
        row.retried = True
    return rows


def stored_uids(model, uids, **owner) -> set:
    """Those of ``uids`` already stored under ``owner``, without loading the rows
    (:func:`stored_rows` for bulk writers such as the archive import)."""
    uids = [uid for uid in uids if uid is not None]
    if not uids:
        return set()
    found = list(_owned(model, uids, owner).values_list("uid", "retry_same_owner"))
    for uid, same_owner in found:
        _check(uid, same_owner)
    return {uid for uid, _ in found}


def stored_row(model, uid, **owner):
    """The row stored under ``uid`` (see :func:`stored_rows`), or None when it is new."""
    if uid is None:
        return None
    return stored_rows(model, [uid], **owner).get(uid)


def is_retry(row) -> bool:
    """Whether a service answered with a row stored before (:func:`stored_rows`)."""
    return getattr(row, "retried", False)


def refuse_foreign(model, sent, stored, **owner) -> None:
    """After a bulk insert that skipped known uids: refuse (409, the caller's
    transaction rolls back) when a skipped uid is another owner's row.
    ``sent`` are the uids given, ``stored`` those inserted."""
    skipped = set(sent) - set(stored)
    if skipped:
        stored_uids(model, skipped, **owner)
