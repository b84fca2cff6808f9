"""Prints the slowest tests of each JUnit XML file pytest wrote (scripts/test.sh
gives one per phase), so the next slow-down is found in the run's last lines.

Usage: python scripts/slowest_tests.py [--top N] FILE.xml...
"""

import argparse
import sys
import xml.etree.ElementTree as ElementTree
from pathlib import Path


def slowest(path: Path, top: int) -> list[tuple[float, str]]:
    cases = []
    for case in ElementTree.parse(path).iter("testcase"):
        module = case.get("classname", "").replace(".", "/")
        cases.append((float(case.get("time") or 0), f"{module}::{case.get('name')}"))
    return sorted(cases, reverse=True)[:top]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--top", type=int, default=10)
    parser.add_argument("files", nargs="+", type=Path)
    args = parser.parse_args()
    for path in args.files:
        if not path.exists():
            continue
        print(f"    slowest tests of {path.stem}:")
        for seconds, name in slowest(path, args.top):
            print(f"    {seconds:8.1f}s  {name}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
