"""Run by :func:`reports.documents.typesetting.typeset` as a child process:
compiles one typst file and writes the PDF to standard output.

    python typst_child.py TEMPLATE ROOT DATA_JSON

It imports nothing of FTT or Django, so it starts in a fraction of a second.
A template error exits with status 3 and typst's message on standard error.
"""

import sys
from pathlib import Path

import typst


def main(template: str, root: str, data_file: str) -> int:
    data = Path(data_file).read_text(encoding="utf-8")
    try:
        pdf = typst.compile(template, root=root, sys_inputs={"data": data})
    except typst.TypstError as exc:
        sys.stderr.write(str(exc))
        return 3
    sys.stdout.buffer.write(pdf)
    return 0


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:]))
