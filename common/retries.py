"""A retried write: a client that lost the answer sends the same uid again.

Every row a client may create carries the uid it chose, and a uid already
stored answers with the row stored first (the API with 200, not 201) instead
of storing it twice.  A uid is only a retry when it names a row of the same
owner (segment, shift) as the request: a uid of another owner's row (another
vehicle's pose, a guessed or reused uid) is refused without that row.
"""

from common.errors import RuleViolation

ANOTHER_OWNER = "This uid belongs to another row; send a new one."


def stored_rows(model, uids, **owner) -> dict:
    """{uid: row stored under it} for those of ``uids`` already stored.  ``owner``
    gives the fields a retry must match (``segment_id=...``); a stored row that
    differs is refused with RuleViolation (HTTP 409), without the row."""
    uids = [uid for uid in uids if uid is not None]
    rows = {row.uid: row for row in model.objects.filter(uid__in=uids)} if uids else {}
    for row in rows.values():
        if any(getattr(row, name) != value for name, value in owner.items()):
            raise RuleViolation({"uid": [ANOTHER_OWNER]})
    return rows


def stored_row(model, uid, **owner):
    """The row stored under ``uid`` (see :func:`stored_rows`), or None when it is new."""
    if uid is None:
        return None
    return stored_rows(model, [uid], **owner).get(uid)
