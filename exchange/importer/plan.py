"""What an import did (or, on a dry run, would do), and why it refused."""

from collections import Counter, defaultdict
from dataclasses import dataclass, field

from django.core.exceptions import ValidationError
from django.utils.translation import gettext_noop

from common.deferred_text import DeferredText, deferred
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
        return str(self.verdict_text())

    def verdict_text(self) -> DeferredText:
        if self.dry_run:
            would = gettext_noop("Would change %(count)s row(s); dry run, nothing written.")
            return deferred(would, count=self.changes())
        return deferred(gettext_noop("Changed %(count)s row(s)."), count=self.changes())

    def lines(self) -> list[str]:
        return count_lines(self.counts)


def describe(exc: ValidationError) -> str:
    """A validation error's messages on one line, field by field."""
    if hasattr(exc, "error_dict"):
        return "; ".join(f"{k}: {' '.join(v)}" for k, v in exc.message_dict.items())
    return " ".join(exc.messages)
