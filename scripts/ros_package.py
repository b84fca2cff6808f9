"""Make a buildable ROS 2 interface package from a folder of .msg/.srv files.

Used by scripts/setup.d/50-ros-interfaces.sh for FTT_ROS_INTERFACES folders
that are not a package already. The package is named after the folder (or its
parent when the folder is called msg/srv); its dependencies are the packages
the definitions name (``std_msgs/Header`` → std_msgs).

    python scripts/ros_package.py FOLDER OUT_DIR   → prints the package name
    python scripts/ros_package.py --check DIR...   → prints the package names

``--check`` refuses, naming the folder and what to do, a folder that does not
exist or holds no definitions, a folder name that is no ROS package name, a
definition rosidl cannot read (when rosidl_adapter is installed) and a
dependency that is neither installed under AMENT_PREFIX_PATH nor one of the
DIRs before it. The build checks each folder the same way.
"""

import contextlib
import io
import os
import re
import shutil
import sys
from pathlib import Path

# rosidl's rule for package names.
PACKAGE_NAME = re.compile(r"^(?!.*__)(?!.*_$)[a-z][a-z0-9_]*$")


class FolderError(Exception):
    pass


CMAKE = """cmake_minimum_required(VERSION 3.8)
project({name})
find_package(ament_cmake REQUIRED)
find_package(rosidl_default_generators REQUIRED)
{finds}
rosidl_generate_interfaces(${{PROJECT_NAME}}
{files}
{deps})
ament_export_dependencies(rosidl_default_runtime)
ament_package()
"""
XML = """<?xml version="1.0"?>
<package format="3">
  <name>{name}</name>
  <version>0.0.0</version>
  <description>Built for FTT from {source}.</description>
  <maintainer email="ftt@example.invalid">FTT</maintainer>
  <license>unknown</license>
  <buildtool_depend>ament_cmake</buildtool_depend>
  <buildtool_depend>rosidl_default_generators</buildtool_depend>
{depends}  <exec_depend>rosidl_default_runtime</exec_depend>
  <member_of_group>rosidl_interface_packages</member_of_group>
  <export><build_type>ament_cmake</build_type></export>
</package>
"""


def definitions(folder: Path) -> tuple[str, list[Path]]:
    """The package name and the .msg/.srv files of a folder of definitions."""
    if not folder.is_dir():
        what = "is not a folder" if folder.exists() else "does not exist"
        raise FolderError(f"{folder} {what}")
    root = folder.parent if folder.name in ("msg", "srv") else folder
    name = root.name
    files = sorted(root.glob("msg/*.msg")) + sorted(root.glob("srv/*.srv"))
    if folder.name in ("msg", "srv") or not files:
        files = sorted(folder.glob("*.msg")) + sorted(folder.glob("*.srv"))
    if not files:
        raise FolderError(
            f"{folder} has no package.xml and no .msg or .srv files (in it or in msg/, srv/)"
        )
    if not PACKAGE_NAME.match(name):
        raise FolderError(
            f"{root}: the package is named after the folder, and {name!r} is no ROS package "
            "name (lower case letters, digits and single underscores, starting with a "
            "letter): rename the folder"
        )
    return name, files


def dependencies(name: str, files: list[Path]) -> dict[str, Path]:
    """{package: the first file naming it} of the other packages the definitions use."""
    deps: dict[str, Path] = {}
    for path in files:
        for line in path.read_text().splitlines():
            m = re.match(r"\s*([A-Za-z]\w*)/(?:msg/)?[A-Za-z]\w*", line.split("#")[0])
            if m and m.group(1) != name:
                deps.setdefault(m.group(1), path)
    return deps


def parse_check(name: str, files: list[Path]) -> None:
    """rosidl's own parser on each file, when it is installed (it comes with
    requirements-rosidl.txt), so a faulty line is named with its file."""
    try:
        from rosidl_adapter.parser import parse_message_string, parse_service_string
    except ImportError:
        return
    for path in files:
        parse = parse_service_string if path.suffix == ".srv" else parse_message_string
        try:
            # It also prints the error itself; once is enough.
            with contextlib.redirect_stderr(io.StringIO()):
                parse(name, path.stem, path.read_text())
        except Exception as exc:
            raise FolderError(f"{path}: {exc}") from None


def installed(package: str) -> bool:
    prefixes = [p for p in os.environ.get("AMENT_PREFIX_PATH", "").split(os.pathsep) if p]
    return any((Path(p) / "share" / package / "package.xml").exists() for p in prefixes)


def check(folder: Path, known: set[str]) -> str:
    """The package name of ``folder`` (a package or a folder of definitions);
    FolderError saying what is wrong. ``known``: packages built before it."""
    folder = folder.resolve()
    if (folder / "package.xml").is_file():
        m = re.search(r"<name>\s*([^<\s]+)\s*</name>", (folder / "package.xml").read_text())
        if not m:
            raise FolderError(f"{folder}/package.xml names no package")
        return m.group(1)
    name, files = definitions(folder)
    parse_check(name, files)
    own = {path.stem for path in files if path.suffix == ".msg"}
    for path in files:
        for line in path.read_text().splitlines():
            m = re.match(r"\s*([A-Z]\w*)\s*(\[[^\]]*\])?\s+\w", line.split("#")[0])
            if m and m.group(1) not in own:
                hint = " (ROS 2 spells it std_msgs/Header)" if m.group(1) == "Header" else ""
                raise FolderError(
                    f"{path} uses {m.group(1)}, which is no message of {folder}{hint}"
                )
    for dep, path in dependencies(name, files).items():
        if dep not in known and not installed(dep):
            raise FolderError(
                f"{path} uses {dep}, which is not installed in FTT's environment: add its "
                "package or folder of definitions to FTT_ROS_INTERFACES, before this one"
            )
    return name


def make_package(folder: Path, out: Path) -> str:
    folder = folder.resolve()
    name, files = definitions(folder)
    deps_sorted = sorted(dependencies(name, files))
    out.mkdir(parents=True, exist_ok=True)
    listed = []
    for path in files:
        kind = "srv" if path.suffix == ".srv" else "msg"
        (out / kind).mkdir(exist_ok=True)
        shutil.copy(path, out / kind / path.name)
        listed.append(f'  "{kind}/{path.name}"')
    (out / "CMakeLists.txt").write_text(
        CMAKE.format(
            name=name,
            finds="".join(f"find_package({d} REQUIRED)\n" for d in deps_sorted),
            files="\n".join(listed),
            deps=f"  DEPENDENCIES {' '.join(deps_sorted)}\n" if deps_sorted else "",
        )
    )
    (out / "package.xml").write_text(
        XML.format(
            name=name,
            source=folder,
            depends="".join(f"  <depend>{d}</depend>\n" for d in deps_sorted),
        )
    )
    return name


def main(args: list[str]) -> None:
    try:
        if args[:1] == ["--check"]:
            known: set[str] = set()
            for folder in args[1:]:
                name = check(Path(folder), known)
                known.add(name)
                print(name)
        else:
            print(make_package(Path(args[0]), Path(args[1])))
    except FolderError as exc:
        sys.exit(str(exc))


if __name__ == "__main__":
    main(sys.argv[1:])
