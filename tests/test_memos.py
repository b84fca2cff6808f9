"""The per-process memos the tests forget between tests are all there are: a
memo left out would carry one test's tokens or segments into the next."""

import importlib
from pathlib import Path

from django.conf import settings

from common.memo import Expiring
from tests.support.caches import MEMOS


def test_every_memo_of_the_code_is_forgotten_between_tests():
    root = Path(settings.BASE_DIR)
    held = set()
    for path in root.glob("*/**/*.py"):
        parts = path.relative_to(root).with_suffix("").parts
        if parts[0] not in {"tests", "benchmarks", ".venv"} and "Expiring(" in path.read_text():
            module = importlib.import_module(".".join(parts))
            held |= {id(v) for v in vars(module).values() if isinstance(v, Expiring)}
    assert held == {id(m) for m in MEMOS}
