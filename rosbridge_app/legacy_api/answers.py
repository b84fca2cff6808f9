"""The original's answer shapes: a JSON string tagged ``[INFO]``/``[WARN]`` for
success, ``{"message": "[ERROR] (<kind>): <text>"}`` for a refusal. The node
parses the tag for its log level and treats 200 as done, 400 as refused."""

from rest_framework.response import Response

from common.api.errors import exception_handler


class LegacyRefusal(Exception):
    def __init__(self, kind: str, text: str, status: int = 400):
        super().__init__(text)
        self.kind, self.text, self.status = kind, text, status


def info(text: str) -> Response:
    return Response(f"[INFO]: {text}")


def warn(text: str) -> Response:
    return Response(f"[WARN]: {text}")


def refusal(exc: Exception, context: dict) -> Response | None:
    """FTT's own answer to ``exc``, in the original's shape (None: not handled)."""
    if isinstance(exc, LegacyRefusal):
        return _message(exc.kind, exc.text, exc.status)
    answer = exception_handler(exc, context)
    if answer is None:
        return None
    status = answer.status_code
    # The node knows 200 and 400; authentication, throttling and a busy
    # server keep their own codes (it logs those as "server unavailable").
    if status not in (401, 403, 429, 503):
        status = 400
    kind = {401: "AuthError", 403: "AuthError", 429: "Throttled", 503: "Busy"}.get(
        status, "RuleError"
    )
    reshaped = _message(kind, answer.data.get("detail") or "Refused.", status)
    for header in ("Retry-After", "WWW-Authenticate"):
        if header in answer:
            reshaped[header] = answer[header]
    return reshaped


def _message(kind: str, text: str, status: int) -> Response:
    return Response({"message": f"[ERROR] ({kind}): {text}"}, status=status)
