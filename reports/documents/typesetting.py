"""Setting a document with typst.

User text never passes through markup: the template receives one JSON document
(``sys.inputs.data``) and places its strings as plain text, so any character,
from umlauts and CJK to ``#``, ``$``, ``\\`` or ``<b>``, appears as written.

typst runs in a child process (``typst_child.py``): the binding keeps what the
last ten compilations memoized for as long as its process lives, which in the
job worker would be ten reports' worth of memory (docs/report.md).
"""

import json
import shutil
import subprocess
import sys
from pathlib import Path

from django.utils.translation import gettext_noop

from reports.documents.options import ReportError

TEMPLATE_DIR = Path(__file__).resolve().parent.parent / "templates_typst"
CHILD = Path(__file__).resolve().with_name("typst_child.py")


def typeset(template: str, data: dict, root: Path) -> bytes:
    """The PDF of ``template`` (a file of TEMPLATE_DIR) filled with ``data``; the
    pictures it names are files in ``root``."""
    shutil.copy(TEMPLATE_DIR / template, root / template)
    data_file = root / "data.json"
    data_file.write_text(json.dumps(data, ensure_ascii=False), encoding="utf-8")
    # -I: the child sees neither the working directory nor PYTHON* variables.
    # Its own session: a Ctrl-C at the job worker's terminal lets the worker
    # finish the report at hand, as it promises, instead of killing typst.
    done = subprocess.run(
        [sys.executable, "-I", str(CHILD), str(root / template), str(root), str(data_file)],
        capture_output=True,
        check=False,
        start_new_session=True,
    )
    if done.returncode != 0:  # a template bug (never user text), or the child was killed
        message = done.stderr.decode("utf-8", "replace").strip() or f"exit {done.returncode}"
        raise ReportError(gettext_noop("Typesetting failed: %(exc)s"), exc=message)
    return done.stdout
