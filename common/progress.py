"""The one-line progress bar of the management commands, drawn on a terminal only.

Redrawn with carriage returns, a bar is useful to a person watching and noise
in a log file or a CI transcript, so off a terminal it stays silent; the
commands print their result either way.
"""


class ProgressBar:
    def __init__(self, stream, width: int = 30):
        self.stream = stream
        self.width = width
        self.enabled = stream.isatty()

    def show(self, fraction: float, *, before: str = "", after: str = "") -> None:
        if not self.enabled:
            return
        fraction = min(max(fraction, 0.0), 1.0)
        filled = round(self.width * fraction)
        self.stream.write(f"\r{before}[{'#' * filled}{'-' * (self.width - filled)}] {after}")
        if fraction >= 1.0:
            self.stream.write("\n")
        self.stream.flush()

    def __call__(self, fraction: float, step) -> None:
        """The report renderer's callback: a fraction and what is being done
        (common.deferred_text.DeferredText, said in the command's language)."""
        self.show(fraction, after=f"{100 * fraction:3.0f}% {str(step)[:40]:<40}")

    def count(self, label: str, done: int, total: int) -> None:
        """A bar for ``done`` of ``total`` things, e.g. messages read from a bag."""
        self.show(done / max(total, 1), before=f"{label} ", after=f"{done}/{total}")
