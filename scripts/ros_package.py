"""Make a buildable ROS 2 interface package from a folder of .msg/.srv files.

Used by scripts/setup.d/50-ros-interfaces.sh for FTT_ROS_INTERFACES folders
that are not a package already. The package is named after the folder (or its
parent when the folder is called msg/srv); its dependencies are the packages
the definitions name (``std_msgs/Header`` → std_msgs).

    python scripts/ros_package.py FOLDER OUT_DIR   → prints the package name
"""

import re
import shutil
import sys
from pathlib import Path

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


def make_package(folder: Path, out: Path) -> str:
    folder = folder.resolve()
    root = folder.parent if folder.name in ("msg", "srv") else folder
    name = root.name
    files = sorted(root.glob("msg/*.msg")) + sorted(root.glob("srv/*.srv"))
    if folder.name in ("msg", "srv") or not files:
        files = sorted(folder.glob("*.msg")) + sorted(folder.glob("*.srv"))
    if not files:
        sys.exit(f"no .msg or .srv files in {folder}")
    deps = set()
    for path in files:
        for line in path.read_text().splitlines():
            m = re.match(r"\s*([A-Za-z]\w*)/(?:msg/)?[A-Za-z]\w*", line.split("#")[0])
            if m and m.group(1) != name:
                deps.add(m.group(1))
    out.mkdir(parents=True, exist_ok=True)
    listed = []
    for path in files:
        kind = "srv" if path.suffix == ".srv" else "msg"
        (out / kind).mkdir(exist_ok=True)
        shutil.copy(path, out / kind / path.name)
        listed.append(f'  "{kind}/{path.name}"')
    deps_sorted = sorted(deps)
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


if __name__ == "__main__":
    print(make_package(Path(sys.argv[1]), Path(sys.argv[2])))
