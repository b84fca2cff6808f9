"""The uid sum a report's digest reads: order-free, additive, and changed by
any uid added, removed or replaced."""

import hashlib
import random
import uuid

from common.uid_sums import EMPTY, combined, uid_sum


def test_a_sum_ignores_order_and_adds_up_from_parts():
    rnd = random.Random(4)
    uids = [uuid.UUID(int=rnd.getrandbits(128), version=4) for _ in range(500)]
    whole = combined(uid_sum(uids))
    shuffled = uids[:]
    rnd.shuffle(shuffled)
    assert combined(uid_sum(shuffled)) == whole
    assert combined(uid_sum(uids[:123]), uid_sum(uids[123:])) == whole
    assert combined(uid_sum(str(u) for u in uids)) == whole
    assert combined(uid_sum([])) == EMPTY


def test_one_uid_is_the_sha256_of_its_bytes_and_any_change_shows():
    uid = uuid.UUID("6f1c2d3e-4a5b-4c6d-8e7f-901234567890")
    assert combined(uid_sum([uid])) == hashlib.sha256(uid.bytes).hexdigest()
    uids = [uuid.UUID(int=i, version=4) for i in range(1, 200)]
    whole = combined(uid_sum(uids))
    assert combined(uid_sum(uids[:-1])) != whole
    assert combined(uid_sum([*uids[:-1], uuid.UUID(int=999, version=4)])) != whole
    # A uid stored twice would count twice: writers store each uid once.
    assert combined(uid_sum([*uids, uids[0]])) != whole
