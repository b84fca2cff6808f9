"""No robot token in a log line: the original FTT's robots name theirs in the
path (``/legacy/<token>/pose``), and paths reach the access log and Django's
request warnings. Every such line is written with ``/legacy/***/`` instead.

Plain ``logging``, no Django: Gunicorn's hook (``ftt_site/server/gunicorn.conf.py``)
puts the filter on the server's own handlers, the settings' ``LOGGING`` on
FTT's.
"""

import logging
import re

LEGACY_TOKEN = re.compile(r"(/legacy/)[^/\s\"'?#]+")


def masked(text: str) -> str:
    return LEGACY_TOKEN.sub(r"\1***", text)


class MaskRobotTokens(logging.Filter):
    def filter(self, record: logging.LogRecord) -> bool:
        message = record.getMessage()
        hidden = masked(message)
        if hidden != message:
            record.msg, record.args = hidden, None
        return True
