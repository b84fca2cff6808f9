"""Setting a document with typst.

User text never passes through markup: the template receives one JSON document
(``sys.inputs.data``) and places its strings as plain text, so any character,
from umlauts and CJK to ``#``, ``$``, ``\\`` or ``<b>``, appears as written.
"""

import json
import shutil
from pathlib import Path

import typst
from django.utils.translation import gettext_noop

from reports.documents.options import ReportError

TEMPLATE_DIR = Path(__file__).resolve().parent.parent / "templates_typst"


def typeset(template: str, data: dict, root: Path) -> bytes:
    """The PDF of ``template`` (a file of TEMPLATE_DIR) filled with ``data``; the
    pictures it names are files in ``root``."""
    shutil.copy(TEMPLATE_DIR / template, root / template)
    try:
        return typst.compile(
            str(root / template),
            root=str(root),
            sys_inputs={"data": json.dumps(data, ensure_ascii=False)},
        )
    except typst.TypstError as exc:  # a template bug, never user text
        raise ReportError(gettext_noop("Typesetting failed: %(exc)s"), exc=str(exc)) from exc
