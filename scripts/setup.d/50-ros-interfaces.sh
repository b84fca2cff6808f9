# shellcheck shell=bash
# Hook of scripts/setup.sh (also runs on its own: bash scripts/setup.d/50-ros-interfaces.sh).
# Builds the ROS message packages that have no wheel (ros_interfaces/tf2_msgs,
# ros_interfaces/industrial_msgs) into the virtualenv, where the rclpy wheels
# already look for libraries. Skipped when the build inputs are unchanged,
# when the interpreter already imports both packages from elsewhere (a native
# /opt/ros/jazzy), or when there is no rclpy at all (e.g. an aarch64 machine
# without ROS: the collector cannot run there anyway).
if [ -z "${FTT_ROOT:-}" ]; then
    FTT_SCRIPT=ros-interfaces
    # shellcheck source=scripts/lib.sh
    source "$(dirname "${BASH_SOURCE[0]}")/../lib.sh"
    FTT_PY=$FTT_VENV/bin/python
fi

_ftt_ros_interfaces() {
    local src=$FTT_ROOT/ros_interfaces build venv_site stamp pkg
    if ! "$FTT_PY" -c 'import rclpy' >/dev/null 2>&1; then
        ftt_log "no rclpy in $FTT_PY: skipping the ROS interface build"
        return 0
    fi
    venv_site=$("$FTT_PY" -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')
    # A native ROS install provides both packages itself; do not shadow them.
    if "$FTT_PY" - "$venv_site" <<'PY' >/dev/null 2>&1; then
import sys, tf2_msgs.msg, industrial_msgs.msg
site = sys.argv[1]
sys.exit(0 if not tf2_msgs.__file__.startswith(site) else 1)
PY
        ftt_log "tf2_msgs and industrial_msgs come from the system ROS install"
        return 0
    fi
    stamp=$({ "$FTT_PY" -VV; cat "$FTT_ROOT/requirements-rosidl.txt";
        find "$src" -type f | LC_ALL=C sort | xargs cat; } | sha256sum | cut -d' ' -f1)
    if ftt_stamp_ok ros-interfaces "$stamp" &&
        "$FTT_PY" -c 'import tf2_msgs.msg, industrial_msgs.msg' >/dev/null 2>&1; then
        ftt_log "ROS interfaces: already built"
        return 0
    fi
    command -v cmake >/dev/null 2>&1 && command -v g++ >/dev/null 2>&1 ||
        ftt_apt_ensure cmake g++
    ftt_log "pip install --require-hashes -r requirements-rosidl.txt"
    "$FTT_PY" -m pip install -q --disable-pip-version-check --require-hashes \
        -r "$FTT_ROOT/requirements-rosidl.txt"
    # The wheels' exported CMake targets name the include directories of the
    # machine that built them; point them at this interpreter and numpy.
    local py_inc np_inc
    py_inc=$("$FTT_PY" -c 'import sysconfig; print(sysconfig.get_paths()["include"])')
    np_inc=$("$FTT_PY" -c 'import numpy; print(numpy.get_include())')
    find "$FTT_VENV/share" -path '*/cmake/*rosidl_generator_py*Export*.cmake' -print0 |
        xargs -0 -r sed -i -E \
            -e "s#/opt/python/cp[0-9]+-cp[0-9]+/include/python[0-9.]+#$py_inc#g" \
            -e "s#/opt/python/cp[0-9]+-cp[0-9]+/lib/python[0-9.]+/site-packages/numpy/_core/include#$np_inc#g"
    build=$(mktemp -d "${TMPDIR:-/tmp}/ftt-rosidl.XXXXXX")
    for pkg in tf2_msgs industrial_msgs; do
        ftt_log "building $pkg"
        (
            export AMENT_PREFIX_PATH=$FTT_VENV CMAKE_PREFIX_PATH=$FTT_VENV
            cmake -S "$src/$pkg" -B "$build/$pkg" -DCMAKE_INSTALL_PREFIX="$FTT_VENV" \
                -DPython3_EXECUTABLE="$FTT_PY" -DBUILD_TESTING=OFF \
                -DCMAKE_BUILD_TYPE=Release >"$build/$pkg.log" 2>&1 &&
                cmake --build "$build/$pkg" -j "$(nproc)" >>"$build/$pkg.log" 2>&1 &&
                cmake --install "$build/$pkg" >>"$build/$pkg.log" 2>&1
        ) || {
            tail -n 30 "$build/$pkg.log" >&2
            ftt_die "building $pkg failed (log: $build/$pkg.log)"
        }
    done
    "$FTT_PY" -c 'import tf2_msgs.msg, industrial_msgs.msg' ||
        ftt_die "tf2_msgs/industrial_msgs were built but do not import"
    rm -rf "$build"
    ftt_stamp_write ros-interfaces "$stamp"
    ftt_log "ROS interfaces built into $FTT_VENV"
}
_ftt_ros_interfaces
