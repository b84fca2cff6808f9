"""typst runs in a child process for each document: the text arrives as written,
a template error is a clear refusal, and the memory typst keeps leaves with
the child instead of staying in the job worker."""

import json
import subprocess
import sys
from pathlib import Path

import pytest

from reports.documents import typesetting
from reports.documents.options import ReportError
from tests.support.pdf import pdf_text

LINES = '#let d = json(bytes(sys.inputs.data))\n#for line in d.at("lines") [#line \\ ]\n'
TITLE = 'Prüfung #1: $x$ <b> \\ "Übergabe" 测试'


@pytest.fixture
def templates(tmp_path, monkeypatch) -> Path:
    directory = tmp_path / "templates"
    directory.mkdir()
    monkeypatch.setattr(typesetting, "TEMPLATE_DIR", directory)
    return directory


def root_of(tmp_path: Path, name: str) -> Path:
    root = tmp_path / name
    root.mkdir()
    return root


def run_probe(probe: str, templates: Path, root: Path) -> subprocess.CompletedProcess:
    """``probe`` in a fresh interpreter, given the templates and a root, with the
    lines template; in a process group of its own, so a Ctrl-C it sends reaches
    only itself."""
    (templates / "lines.typ").write_text(LINES, encoding="utf-8")
    return subprocess.run(
        [sys.executable, "-c", probe, str(templates), str(root)],
        capture_output=True,
        text=True,
        cwd=Path(__file__).resolve().parents[2],
        start_new_session=True,
    )


def test_the_text_arrives_in_the_pdf_as_written(tmp_path, templates):
    (templates / "t.typ").write_text(
        '#let d = json(bytes(sys.inputs.data))\n#d.at("title")\n', encoding="utf-8"
    )
    pdf = typesetting.typeset("t.typ", {"title": TITLE}, root_of(tmp_path, "a"))
    assert pdf.startswith(b"%PDF")
    assert TITLE in pdf_text(pdf, tmp_path, layout=False)


def test_a_template_error_is_refused_with_typsts_message(tmp_path, templates):
    (templates / "broken.typ").write_text("#undefined_thing\n", encoding="utf-8")
    with pytest.raises(ReportError) as refused:
        typesetting.typeset("broken.typ", {}, root_of(tmp_path, "b"))
    said = str(refused.value)
    assert said.startswith("Typesetting failed: ") and "unknown variable: undefined_thing" in said


MEMORY_PROBE = """
import json, pathlib, sys
import django
django.setup()
from reports.documents import typesetting

def resident_mb():
    for line in open("/proc/self/status"):
        if line.startswith("VmRSS"):
            return int(line.split()[1]) / 1024

typesetting.TEMPLATE_DIR = pathlib.Path(sys.argv[1])
sizes = []
for k in range(6):
    root = pathlib.Path(sys.argv[2]) / str(k)
    root.mkdir()
    lines = [f"report {k}, line {i}: {i * k}" for i in range(3000)]
    typesetting.typeset("lines.typ", {"lines": lines}, root)
    sizes.append(resident_mb())
print(json.dumps(sizes))
"""


def test_a_process_that_makes_many_pdfs_does_not_keep_typsts_memory(tmp_path, templates):
    # typst's memo cache, were typst run in this process, would keep each of
    # these documents' work for the next ten compilations.
    done = run_probe(MEMORY_PROBE, templates, root_of(tmp_path, "m"))
    assert done.returncode == 0, done.stderr[-500:]
    sizes = json.loads(done.stdout.strip().splitlines()[-1])
    assert sizes[-1] - sizes[0] < 15, sizes


INTERRUPT_PROBE = """
import os, pathlib, signal, sys, threading
import django
django.setup()
from reports.documents import typesetting

signal.signal(signal.SIGINT, lambda *_: None)  # as the job worker: finish the job at hand
typesetting.TEMPLATE_DIR = pathlib.Path(sys.argv[1])
lines = [f"line {i}" for i in range(20000)]
sent = threading.Event()


def typst_runs():
    for task in pathlib.Path("/proc/self/task").iterdir():
        for pid in (task / "children").read_text().split():
            try:
                command = pathlib.Path(f"/proc/{pid}/cmdline").read_bytes()
            except FileNotFoundError:  # a child that has just ended
                continue
            if str(typesetting.CHILD).encode() in command:
                return True
    return False


def interrupt_once_typst_runs():
    while not typst_runs():
        pass
    os.killpg(0, signal.SIGINT)
    sent.set()


threading.Thread(target=interrupt_once_typst_runs, daemon=True).start()
pdf = typesetting.typeset("lines.typ", {"lines": lines}, pathlib.Path(sys.argv[2]))
print(pdf[:5].decode(), sent.is_set())
"""


def test_a_ctrl_c_at_the_workers_terminal_does_not_stop_the_pdf_being_set(tmp_path, templates):
    done = run_probe(INTERRUPT_PROBE, templates, root_of(tmp_path, "i"))
    assert done.stdout.split() == ["%PDF-", "True"], done.stderr[-500:]
