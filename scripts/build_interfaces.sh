#!/usr/bin/env bash
# Builds ROS 2 interface packages into PREFIX with the rosidl generators of
# FTT's virtualenv (requirements-rosidl.txt, installed by
# scripts/setup.d/50-ros-interfaces.sh):
#     bash scripts/build_interfaces.sh PREFIX DIR...
# A DIR is a ROS 2 package (package.xml) or a folder of .msg/.srv files, made
# into a package named after the folder (scripts/ros_package.py). A process
# that uses PREFIX other than the virtualenv needs PYTHONPATH=PREFIX/lib/pythonX.Y/site-packages,
# LD_LIBRARY_PATH=PREFIX/lib and AMENT_PREFIX_PATH=PREFIX:... at its start.
# FTT_ROS_INSTALLED=FILE: every file installed is appended to FILE, one a line.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
venv=$(readlink -f "${FTT_VENV:-$root/.venv}")
py=$venv/bin/python
prefix=$1
shift
export AMENT_PREFIX_PATH=$prefix:$venv
# Every folder checked before the first one is built: a wrong one is named at once.
"$py" "$root/scripts/ros_package.py" --check "$@" >/dev/null
build=$(mktemp -d "${TMPDIR:-/tmp}/ftt-rosidl.XXXXXX")
trap 'rm -rf "$build"' EXIT
for dir in "$@"; do
    if [ -f "$dir/package.xml" ]; then
        pkg=$(basename "$dir")
        src=$dir
    else
        src=$build/src/$(basename "$dir")
        pkg=$("$py" "$root/scripts/ros_package.py" "$dir" "$src")
    fi
    echo "building $pkg into $prefix" >&2
    (
        export CMAKE_PREFIX_PATH=$prefix:$venv
        cmake -S "$src" -B "$build/$pkg" -DCMAKE_INSTALL_PREFIX="$prefix" \
            -DPython3_EXECUTABLE="$py" -DBUILD_TESTING=OFF \
            -DCMAKE_BUILD_TYPE=Release >"$build/$pkg.log" 2>&1 &&
            cmake --build "$build/$pkg" -j "$(nproc)" >>"$build/$pkg.log" 2>&1 &&
            cmake --install "$build/$pkg" >>"$build/$pkg.log" 2>&1 &&
            if [ -n "${FTT_ROS_INSTALLED:-}" ]; then { cat "$build/$pkg/install_manifest.txt"; echo; } >>"$FTT_ROS_INSTALLED"; fi
    ) || {
        # The CMake log names the missing package or the faulty definition.
        tail -n 30 "$build/$pkg.log" >&2
        trap - EXIT
        echo "building $pkg from $dir failed (build folder kept: $build)" >&2
        exit 1
    }
done
