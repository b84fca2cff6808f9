"""What an import did (or, on a dry run, would do), and why it refused."""

from collections import Counter, defaultdict
from dataclasses import dataclass, field

from django.core.exceptions import ValidationError
from django.utils.translation import gettext_noop

from common.said import Said, said
from exchange.counts import count_lines


class ImportRefused(Exception):
    """The data cannot be imported as it is; nothing was changed."""


class MalformedRecord(ImportRefused):
    """A record or file has the wrong shape (a bad request, not a conflict with data here)."""


@dataclass
class Plan:
    dry_run: bool = False
    counts: dict = field(default_factory=lambda: defaultdict(Counter))

    def note(self, table: str, outcome: str, n: int = 1) -> None:
        if n:
            self.counts[table][outcome] += n

    def total(self, outcome: str) -> int:
        return sum(c[outcome] for c in self.counts.values())

    def changes(self) -> int:
        return self.total("added") + self.total("updated")

    def verdict(self) -> str:
        """In the active language."""
        return str(self.said())

    def said(self) -> Said:
        if self.dry_run:
            would = gettext_noop("Would change %(count)s row(s); dry run, nothing written.")
            return said(would, count=self.changes())
        return said(gettext_noop("Changed %(count)s row(s)."), count=self.changes())

    def lines(self) -> list[str]:
        return count_lines(self.counts)


def describe(exc: ValidationError) -> str:
    """A validation error's messages on one line, field by field."""
    if hasattr(exc, "error_dict"):
        return "; ".join(f"{k}: {' '.join(v)}" for k, v in exc.message_dict.items())
    return " ".join(exc.messages)
