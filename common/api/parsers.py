import io

from django.utils.translation import gettext as _
from rest_framework import parsers
from rest_framework.exceptions import ParseError

from common.text import LONE_SURROGATE, holds_lone_surrogate, may_hold_surrogate


class JSONParser(parsers.JSONParser):
    """DRF's parser, plus: nesting deeper than Python's recursion limit and text
    with a lone surrogate (common.text) are a 400, not a 500."""

    def parse(self, stream, media_type=None, parser_context=None):
        body = stream.read()
        try:
            data = super().parse(io.BytesIO(body), media_type, parser_context)
        except RecursionError:
            raise ParseError(_("JSON parse error - nested too deeply.")) from None
        if may_hold_surrogate(body) and holds_lone_surrogate(data):
            raise ParseError(_("JSON parse error - %(reason)s") % {"reason": LONE_SURROGATE})
        return data
