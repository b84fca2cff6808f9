"""An order-free digest of a set of uids: the sum of the SHA-256 values of
their 16 bytes modulo 2**256, written as 64 hex digits.

A sum can be kept as rows arrive in any order and on any installation, and
the sums of parts add up to the sum of the whole, so a report's data digest
reads one number per segment instead of every pose.  It detects a change;
it is not meant to resist someone who can write the database (such a person
can change the rows it covers without touching their uids anyway).
"""

import hashlib
import uuid
from collections.abc import Iterable

_MODULUS = 1 << 256
EMPTY = "0" * 64


def uid_value(uid) -> int:
    """One uid's part of a sum (uuid.UUID or its text): the SHA-256 of its 16 bytes."""
    raw = uid.bytes if isinstance(uid, uuid.UUID) else uuid.UUID(str(uid)).bytes
    return int.from_bytes(hashlib.sha256(raw).digest())


def uid_sum(uids: Iterable) -> int:
    """The sum of ``uids`` as a number."""
    return sum(map(uid_value, uids)) % _MODULUS


def combined(*sums: str | int) -> str:
    """The sum of several sums (hex text or numbers), as hex text."""
    total = sum(int(s, 16) if isinstance(s, str) else s for s in sums)
    return f"{total % _MODULUS:064x}"
