"""What the collector's writer thread knows, for the node's service answers."""


class Status:
    """What the writer thread knows, for service answers (plain attributes: the
    GIL makes single reads and writes safe)."""

    def __init__(self):
        self.leg: str | None = None
        self.database_ok = True
        self.pending = 0
        self.note = ""

    def describe(self) -> str:
        parts = [f"logging into {self.leg}" if self.leg else "no open leg for the vehicle"]
        if not self.database_ok:
            parts.append(f"database unreachable, {self.pending} records spooled")
        elif self.pending:
            parts.append(f"{self.pending} records waiting")
        if self.note:
            parts.append(self.note)
        return "; ".join(parts)
