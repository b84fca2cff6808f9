"""Every file path and dotted name that docs/ and the README put in backticks
names something that exists, so a reader who follows one finds it.

Resolved from the source without importing it (the collector's modules would
need ROS): a path must exist below the checkout; a dotted name that starts
with one of our packages must be a module, a name defined or imported at the
top of one, or a member of a class defined there; ``app.Model`` and
``app.codename`` (a permission) are the two Django forms besides.
"""

import ast
import re
import subprocess
from functools import cache
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
DOCUMENTS = sorted([ROOT / "README.md", *(ROOT / "docs").glob("*.md")])
PACKAGES = {p.parent.name for p in ROOT.glob("*/__init__.py")}
# Top-level folders a documented path may start with: those git keeps, since
# data/ and the like are made at run time.
FOLDERS = {
    name.split("/")[0]
    for name in subprocess.run(
        ["git", "ls-files"], cwd=ROOT, capture_output=True, text=True, check=True
    ).stdout.splitlines()
    if "/" in name
}
FILE_ENDINGS = (
    ".py .js .css .html .md .sh .toml .yaml .yml .json .po .typ .txt .in .cfg .svg .png"
).split()

SPAN = re.compile(r"`([^`\n]+)`")
DOTTED = re.compile(r"[A-Za-z_]\w*(?:\.[A-Za-z_]\w*)+")
# A line reference after a path: `events/rules.py:84` or `:84-90`.
LINE_SUFFIX = re.compile(r":\d+(?:-\d+)?$")


def spans():
    for document in DOCUMENTS:
        text = document.read_text(encoding="utf-8")
        # Fenced blocks hold commands and output, not references.
        text = re.sub(
            r"^```.*?^```", lambda m: "\n" * m.group().count("\n"), text, flags=re.S | re.M
        )
        for match in SPAN.finditer(text):
            line = text.count("\n", 0, match.start()) + 1
            yield f"{document.relative_to(ROOT)}:{line}", match.group(1).strip()


def is_path(span: str) -> bool:
    if any(c in span for c in " <>*{}$|") or span.startswith(("/", "~", ".")):
        return False
    head, _, rest = span.partition("/")
    return bool(rest) and head in FOLDERS


def path_exists(span: str) -> bool:
    """A file or folder of the checkout, ``app/0013`` (a migration),
    ``folder/module.name`` (a name in a module, written as a path), or
    ``folder/test_file.py::test_name`` (a test)."""
    if (ROOT / span).exists():
        return True
    if "::" in span:  # a test, as pytest names it: file::function
        file, _, name = span.partition("::")
        return (ROOT / file).is_file() and name.split("[")[0] in top_names(ROOT / file)
    head, _, last = span.rpartition("/")
    if re.fullmatch(r"\d{4}", last):
        return any((ROOT / head / "migrations").glob(f"{last}_*.py"))
    if "." in last and not last.endswith(tuple(FILE_ENDINGS)):
        return dotted_resolves(span.replace("/", ".").split("(")[0])
    return False


@cache
def module_file(dotted: str) -> Path | None:
    base = ROOT.joinpath(*dotted.split("."))
    for candidate in (base.with_suffix(".py"), base / "__init__.py"):
        if candidate.is_file():
            return candidate
    return None


@cache
def top_names(path: Path) -> dict:
    """Names bound at the top of a module, each with its class body if it is a class."""
    names = {}
    for node in ast.parse(path.read_text(encoding="utf-8")).body:
        if isinstance(node, ast.ClassDef):
            names[node.name] = node
        elif isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
            names[node.name] = None
        elif isinstance(node, ast.Assign | ast.AnnAssign | ast.AugAssign):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            for target in targets:
                for name in ast.walk(target):
                    if isinstance(name, ast.Name):
                        names[name.id] = None
        elif isinstance(node, ast.Import | ast.ImportFrom):
            for alias in node.names:
                names[(alias.asname or alias.name).split(".")[0]] = None
        elif isinstance(node, ast.If | ast.Try):
            # Names bound under a guard (TYPE_CHECKING, an optional import).
            for inner in ast.walk(node):
                if isinstance(inner, ast.ClassDef | ast.FunctionDef):
                    names.setdefault(inner.name, None)
    return names


def class_members(node: ast.ClassDef) -> set:
    members = set()
    for item in node.body:
        if isinstance(item, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
            members.add(item.name)
        elif isinstance(item, ast.Assign | ast.AnnAssign):
            targets = item.targets if isinstance(item, ast.Assign) else [item.target]
            members.update(t.id for t in targets if isinstance(t, ast.Name))
    return members


def model_names(app: str) -> set:
    path = module_file(f"{app}.models")
    return set(top_names(path)) if path else set()


def permission_codenames(app: str) -> set:
    models = ROOT / app / "models"
    files = [*models.glob("*.py")] if models.is_dir() else [ROOT / app / "models.py"]
    text = "\n".join(f.read_text(encoding="utf-8") for f in files if f.is_file())
    declared = set(re.findall(r"\(\s*\"(\w+)\",\s*\"Can ", text))
    defaults = {
        f"{verb}_{name.lower()}"
        for name in model_names(app)
        if name[:1].isupper()
        for verb in ("add", "change", "delete", "view")
    }
    return declared | defaults


def dotted_resolves(name: str) -> bool:
    parts = name.split(".")
    for cut in range(len(parts), 0, -1):
        path = module_file(".".join(parts[:cut]))
        if path is None:
            continue
        rest = parts[cut:]
        if not rest:
            return True
        names = top_names(path)
        if rest[0] not in names:
            break
        node = names[rest[0]]
        if len(rest) == 1 or not isinstance(node, ast.ClassDef):
            # Deeper than a class member is an attribute a value has at run time.
            return True
        return rest[1] in class_members(node)
    if len(parts) == 2 and module_file(parts[0]):
        app, name = parts
        return name in model_names(app) or name in permission_codenames(app)
    return False


def references():
    for where, span in spans():
        if is_path(span):
            yield where, "path", LINE_SUFFIX.sub("", span)
            continue
        span = span.removesuffix("()")
        if span.endswith(tuple(FILE_ENDINGS)) or not DOTTED.fullmatch(span):
            continue
        if span.split(".")[0] in PACKAGES:
            yield where, "name", span


def test_the_documents_name_things_at_all():
    kinds = {kind for _, kind, _ in references()}
    assert kinds == {"path", "name"}


def test_every_documented_path_and_name_exists():
    missing = [
        f"{where}: `{span}`"
        for where, kind, span in references()
        if not (path_exists(span) if kind == "path" else dotted_resolves(span))
    ]
    assert not missing, "documented but not in the code:\n" + "\n".join(missing)


@pytest.mark.parametrize(
    ("name", "exists"),
    [
        ("live.consumers.LiveConsumer", True),
        ("live.consumers.LiveConsumer.connect", True),
        ("live.consumers.LiveConsumer.no_such_method", False),
        ("rosbridge_app.consumers", False),
        ("events.Segment", True),
        ("events.finalise_testevent", True),
        ("events.add_segment", True),
        ("events.fly_segment", False),
    ],
)
def test_a_name_is_resolved_as_a_reader_would(name, exists):
    assert dotted_resolves(name) is exists


@pytest.mark.parametrize(
    ("span", "exists"),
    [
        ("tests/test_docs_names.py::test_every_documented_path_and_name_exists", True),
        ("tests/test_docs_names.py::test_every_documented_path_and_name_exists[x]", True),
        ("tests/test_docs_names.py::test_no_such_test", False),
        ("tests/no_such_file.py::test_every_documented_path_and_name_exists", False),
    ],
)
def test_a_test_is_found_as_pytest_names_it(span, exists):
    assert path_exists(span) is exists
