"""The hashed locks that scripts/setup.sh installs agree with their sources
(requirements*.in): someone who edits a source and forgets scripts/lock.sh is told."""

import re
from pathlib import Path

import pytest
from packaging.requirements import Requirement
from packaging.utils import canonicalize_name

ROOT = Path(__file__).resolve().parent.parent
PAIRS = [
    ("requirements.in", "requirements.txt"),
    ("requirements-dev.in", "requirements-dev.txt"),
    ("requirements-rosidl.in", "requirements-rosidl.txt"),
]
ENTRY = re.compile(r"^([A-Za-z0-9][A-Za-z0-9._-]*)==(\S+)\s*(?:;\s*(.*?))?\s*\\?$")


def source_requirements(name: str) -> list[Requirement]:
    """The requirements a source names, with those of the sources it includes (-r)."""
    found = []
    for line in (ROOT / name).read_text().splitlines():
        line = line.split("#", 1)[0].strip()
        if line.startswith("-r "):
            found += source_requirements(line[3:].strip())
        elif line and not line.startswith("-"):
            found.append(Requirement(line))
    return found


def lock_entries(name: str) -> dict[str, list[tuple[str, str | None, int]]]:
    """Package -> [(version, marker, number of hashes)] of a lock."""
    entries: dict[str, list] = {}
    current = None
    for line in (ROOT / name).read_text().splitlines():
        match = ENTRY.match(line)
        if match:
            package, version, marker = match.groups()
            current = [version, marker, 0]
            entries.setdefault(canonicalize_name(package), []).append(current)
        elif line.strip().startswith("--hash=sha256:") and current is not None:
            current[2] += 1
    return {package: [tuple(e) for e in found] for package, found in entries.items()}


@pytest.mark.parametrize(("source", "lock"), PAIRS, ids=[lock for _, lock in PAIRS])
def test_the_lock_pins_every_source_requirement_within_its_bounds_with_hashes(source, lock):
    entries = lock_entries(lock)
    assert entries and all(hashes for found in entries.values() for *_, hashes in found)
    for requirement in source_requirements(source):
        pinned = entries.get(canonicalize_name(requirement.name))
        assert pinned, f"{requirement.name} of {source} is not in {lock}: run scripts/lock.sh"
        for version, _, _ in pinned:
            assert requirement.specifier.contains(version, prereleases=True), (
                f"{lock} pins {requirement.name}=={version} outside {source}'s "
                f"{requirement.specifier}: run scripts/lock.sh"
            )


@pytest.mark.parametrize("lock", ["requirements-dev.txt", "requirements-rosidl.txt"])
def test_the_other_locks_keep_the_runtime_versions(lock):
    runtime = lock_entries("requirements.txt")
    other = lock_entries(lock)
    for package, found in other.items():
        if package in runtime:
            assert {v for v, *_ in found} <= {v for v, *_ in runtime[package]}, package


def test_the_runtime_lock_has_no_test_only_server():
    # Tests and benchmarks may start daphne; the production server is Gunicorn + Uvicorn.
    runtime = lock_entries("requirements.txt")
    assert "daphne" not in runtime
    assert {"gunicorn", "uvicorn", "uvicorn-worker", "channels"} <= set(runtime)
