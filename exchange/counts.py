"""An import's counts per archive table and outcome, as a table of text lines."""

from django.utils.translation import gettext, gettext_noop

from exchange import records as rec

# "refused": history entries an import leaves out (exchange.importer.history).
OUTCOMES = ("added", "updated", "unchanged", "reused", "refused")
# The column headings; the rows are the archive's table names.
HEADINGS = {
    "added": gettext_noop("added"),
    "updated": gettext_noop("updated"),
    "unchanged": gettext_noop("unchanged"),
    "reused": gettext_noop("reused"),
    "refused": gettext_noop("refused"),
}


def count_lines(counts: dict) -> list[str]:
    """Headed in the active language (the command, the import page, a finished job)."""
    head = f"{'':14}" + "".join(f"{gettext(HEADINGS[o]):>13}" for o in OUTCOMES)
    rows = [head]
    for table in rec.TABLES:
        if table in counts:
            c = counts[table]
            rows.append(f"{table:14}" + "".join(f"{c.get(o, 0):>13}" for o in OUTCOMES))
    return rows
