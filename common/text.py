"""Text a request may carry that nothing downstream can store.

JSON lets a client escape a lone UTF-16 surrogate (``"\\ud800"``); Python
parses it into a str that no UTF-8 encoder, database or zone lookup takes, so
every field that let one through failed later, as a 500. Parsers ask here and
answer 400 instead.
"""

import json

LONE_SURROGATE = "A text holds a lone UTF-16 surrogate (\\ud800-\\udfff), which is no character."


def may_hold_surrogate(body: bytes) -> bool:
    """Cheap test on a UTF-8 JSON body: only a \\u escape can make a surrogate
    (a strict UTF-8 decoder refuses an encoded one)."""
    return b"\\u" in body


def holds_lone_surrogate(data) -> bool:
    """True when a string anywhere in parsed JSON (keys too) is not valid Unicode text."""
    try:
        json.dumps(data, ensure_ascii=False).encode("utf-8")
    except UnicodeEncodeError:
        return True
    return False
