"""Reading reports back the way a person sees them: pdftotext and page images."""

import os
import re
import subprocess
from pathlib import Path

from pypdf import PdfReader

# Not test-results/: pytest-playwright empties that directory when it starts.
ARTIFACTS = Path(os.environ.get("FTT_TEST_ARTIFACTS", "tmp/artifacts")) / "reports"


def pdf_text(pdf: bytes, tmp_path: Path, layout: bool = True) -> str:
    """The text; with ``layout`` table rows stay on one line, without it the
    columns of the title page are read one after the other."""
    path = tmp_path / "report.pdf"
    path.write_bytes(pdf)
    command = ["pdftotext", *(["-layout"] if layout else []), str(path), "-"]
    return subprocess.run(command, check=True, capture_output=True, text=True).stdout


def flat(text: str) -> str:
    """Whitespace collapsed, so text wrapped in a table cell still matches."""
    return re.sub(r"\s+", " ", text)


def has_row(text: str, *cells: str) -> bool:
    """True when one line holds the cells in this order, separated by spaces."""
    pattern = r"\s+".join(re.escape(cell) for cell in cells)
    return any(re.search(pattern, line) for line in text.splitlines())


def page_count(pdf: bytes, tmp_path: Path) -> int:
    path = tmp_path / "count.pdf"
    path.write_bytes(pdf)
    return len(PdfReader(str(path)).pages)


def save_pages(pdf: bytes, name: str, dpi: int = 60) -> list[Path]:
    """Render every page to PNG under the artifacts directory (kept after the run)."""
    target = ARTIFACTS / name
    target.mkdir(parents=True, exist_ok=True)
    for old in target.glob("*.png"):
        old.unlink()
    source = target / "report.pdf"
    source.write_bytes(pdf)
    subprocess.run(
        ["pdftoppm", "-r", str(dpi), "-png", str(source), str(target / "page")], check=True
    )
    return sorted(target.glob("page-*.png"))
