"""CSV that a spreadsheet opens as text, not as formulas (CSV injection).

A cell that starts with ``= + - @``, a tab or a carriage return is run as a
formula by Excel and LibreOffice (``=HYPERLINK(...)`` in a note).  Such text
cells get a leading apostrophe, as OWASP recommends; numbers stay numbers.
"""

import csv
from collections.abc import Iterable, Iterator, Sequence

_FORMULA_START = ("=", "+", "-", "@", "\t", "\r")


def safe_cell(value):
    if isinstance(value, str) and value.startswith(_FORMULA_START):
        return "'" + value
    return value


class SafeWriter:
    """csv.writer whose text cells are neutralised; use it for every CSV export."""

    def __init__(self, out, **kwargs):
        self._writer = csv.writer(out, **kwargs)

    def writerow(self, row):
        return self._writer.writerow([safe_cell(value) for value in row])


class _Line:
    """A file whose ``write`` hands the text back: csv.writer's row, as a string."""

    def write(self, text: str) -> str:
        return text


def csv_rows(rows: Iterable[Sequence]) -> Iterator[str]:
    """``rows`` (the header first) as SafeWriter's CSV, one line at a time."""
    writer = SafeWriter(_Line())
    for row in rows:
        yield writer.writerow(row)
