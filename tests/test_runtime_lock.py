"""What FTT's own code imports is installed by `scripts/run.sh`: every
third-party package imported outside the tests, benchmarks and scripts belongs
to a distribution of the runtime lock (requirements.txt), not only of the test
lock that `.ci/run` installs."""

import ast
import re
from importlib.metadata import packages_distributions
from pathlib import Path

from django.conf import settings

ROOT = Path(settings.BASE_DIR)
# Not FTT's code, or not run by `scripts/run.sh`.
OUTSIDE = {"tests", "benchmarks", "scripts", "node_modules", "ros_interfaces", "data", "tmp"}


def _canonical(name: str) -> str:
    return re.sub(r"[-_.]+", "-", name).lower()


def runtime_lock() -> set[str]:
    text = (ROOT / "requirements.txt").read_text(encoding="utf-8")
    return {_canonical(m) for m in re.findall(r"^([A-Za-z0-9][\w.-]*)(?:\[[^]]*\])?==", text, re.M)}


def production_files():
    for path in ROOT.rglob("*.py"):
        parts = path.relative_to(ROOT).parts
        if parts[0] in OUTSIDE or parts[0].startswith("."):
            continue
        yield path


def imported_top_modules(path: Path) -> set[str]:
    names = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            names |= {alias.name.split(".")[0] for alias in node.names}
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names.add(node.module.split(".")[0])
    return names


def test_every_package_ftts_code_imports_is_in_the_runtime_lock():
    locked = runtime_lock()
    distributions = packages_distributions()
    # Setup builds these message packages itself (scripts/setup.d/50-ros-interfaces.sh).
    built = {p.name for p in (ROOT / "ros_interfaces").iterdir() if p.is_dir()}
    missing = {}
    for path in production_files():
        for module in imported_top_modules(path) - built:
            # The standard library and FTT's own apps have no distribution; a
            # ROS wheel names its module twice (its own metadata and the wheel's).
            dists = distributions.get(module, [])
            if dists and not any(_canonical(d) in locked for d in dists):
                missing.setdefault(
                    f"{module} ({', '.join(dists)})", path.relative_to(ROOT).as_posix()
                )
    assert not missing, "imported by FTT's code, missing from requirements.txt: " + repr(missing)


def test_the_check_sees_a_package_only_the_test_lock_has(tmp_path):
    sample = tmp_path / "sample.py"
    sample.write_text("import pytest\nfrom django.db import models\nimport json\n")
    modules = imported_top_modules(sample)
    assert modules == {"pytest", "django", "json"}
    distributions = packages_distributions()
    assert "pytest" not in runtime_lock() and "pytest" in distributions["pytest"]
    assert "django" in runtime_lock()
