# shellcheck shell=bash
# Hook of scripts/setup.sh (also runs on its own: bash scripts/setup.d/50-ros-interfaces.sh).
# Builds the ROS message packages that have no wheel (ros_interfaces/tf2_msgs,
# ros_interfaces/industrial_msgs) into the virtualenv, where the rclpy wheels
# already look for libraries. Skipped when the build inputs are unchanged,
# when the interpreter already imports both packages from elsewhere (a native
# /opt/ros/jazzy), or when there is no rclpy at all (e.g. an aarch64 machine
# without ROS: the collector cannot run there anyway).
# FTT_ROS_INTERFACES=DIR[:DIR...] adds the robot team's own interface packages
# or folders of .msg/.srv files (docs/collector.md: custom message types); later
# setups without the variable build the same folders again.
# FTT_ROS_PREFIX=DIR builds into DIR instead of the virtualenv, with the rosidl
# tools an earlier setup installed into the virtualenv (the tests build their
# fixtures so).
# On its own (also from a process that scripts/test.sh started, where FTT_ROOT
# is in the environment but the helpers are not) it loads the helpers itself.
if ! declare -F ftt_die >/dev/null; then
    FTT_SCRIPT=ros-interfaces
    # shellcheck source=scripts/lib.sh
    source "$(dirname "${BASH_SOURCE[0]}")/../lib.sh"
    FTT_PY=$FTT_VENV/bin/python
fi

_ftt_ros_interfaces() {
    local src=$FTT_ROOT/ros_interfaces venv_site stamp dir names name
    local prefix=${FTT_ROS_PREFIX:-$FTT_VENV} site
    [[ $prefix == /* ]] || prefix=$PWD/$prefix
    site=$prefix/lib/$("$FTT_PY" -c 'import sys; print(f"python{sys.version_info[0]}.{sys.version_info[1]}")')/site-packages
    local dirs=("$src/tf2_msgs" "$src/industrial_msgs") extra=() teams=()
    # The robot team's own interfaces: ROS 2 packages or folders of .msg files;
    # setup.sh runs in FTT's folder, a relative one is relative to where it started.
    # Remembered beside the build, so that a later setup (every scripts/run.sh)
    # without the variable keeps them; FTT_ROS_INTERFACES= (empty) forgets them.
    local remembered=$prefix/.ftt-ros-interfaces
    if [ -z "${FTT_ROS_INTERFACES+set}" ] && [ -s "$remembered" ]; then
        mapfile -t teams <"$remembered"
        ftt_log "FTT_ROS_INTERFACES from the last setup: ${teams[*]}"
    else
        IFS=: read -r -a extra <<<"${FTT_ROS_INTERFACES:-}"
        for dir in "${extra[@]}"; do
            [ -n "$dir" ] || continue
            [[ $dir == /* ]] || dir=${FTT_CALLER_DIR:-$PWD}/$dir
            teams+=("$dir")
        done
    fi
    if ! "$FTT_PY" -c 'import rclpy' >/dev/null 2>&1; then
        ftt_log "no rclpy in $FTT_PY: skipping the ROS interface build"
        [ ${#teams[@]} -eq 0 ] || ftt_log "FTT_ROS_INTERFACES not built: no rclpy to build them for"
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
        [ ${#teams[@]} -eq 0 ] || ftt_log "FTT_ROS_INTERFACES not built: with a system ROS," \
            "build them with colcon (docs/collector.md: custom message types)"
        return 0
    fi
    dirs+=("${teams[@]}")
    # Names each package, or says what is wrong with a folder, before anything is built.
    names=$(AMENT_PREFIX_PATH=$prefix:$FTT_VENV "$FTT_PY" "$FTT_ROOT/scripts/ros_package.py" \
        --check "${dirs[@]}") ||
        ftt_die "FTT_ROS_INTERFACES: a folder cannot be built (above; docs/collector.md: custom message types)"
    stamp=$({ "$FTT_PY" -VV; cat "$FTT_ROOT/requirements-rosidl.txt";
        find "${dirs[@]}" -type f | LC_ALL=C sort | xargs cat; } | sha256sum | cut -d' ' -f1)
    if FTT_VENV=$prefix ftt_stamp_ok ros-interfaces "$stamp" &&
        _ftt_prefix_python -c 'import tf2_msgs.msg, industrial_msgs.msg' >/dev/null 2>&1; then
        ftt_log "ROS interfaces: already built"
    elif _ftt_ros_restore; then
        # The tests build interfaces of their own with the tools.
        [ "${FTT_SETUP_MODE:-run}" != test ] || [ "$prefix" != "$FTT_VENV" ] || _ftt_rosidl_tools
    elif [ "$prefix" != "$FTT_VENV" ]; then
        "$FTT_PY" -c 'import rosidl_adapter' 2>/dev/null ||
            ftt_die "FTT_ROS_PREFIX needs the rosidl tools in $FTT_VENV: run scripts/setup.sh first"
        _ftt_ros_build
    else
        _ftt_rosidl_tools
        _ftt_ros_build
    fi
    if [ ${#teams[@]} -gt 0 ]; then
        printf '%s\n' "${teams[@]}" >"$remembered"
    else
        rm -f "$remembered"
    fi
}

_ftt_rosidl_tools() { # the rosidl generators and CMake helpers, into the virtualenv
    command -v cmake >/dev/null 2>&1 && command -v g++ >/dev/null 2>&1 ||
        ftt_apt_ensure cmake g++
    ftt_log "uv pip install --require-hashes -r requirements-rosidl.txt"
    ftt_uv_ensure
    ftt_uv_install -r "$FTT_ROOT/requirements-rosidl.txt"
    # The wheels' exported CMake targets name the include directories of the
    # machine that built them; point them at this interpreter and numpy.
    local py_inc np_inc
    py_inc=$("$FTT_PY" -c 'import sysconfig; print(sysconfig.get_paths()["include"])')
    np_inc=$("$FTT_PY" -c 'import numpy; print(numpy.get_include())')
    find "$FTT_VENV/share" -path '*/cmake/*rosidl_generator_py*Export*.cmake' -print0 |
        xargs -0 -r sed -i -E \
            -e "s#/opt/python/cp[0-9]+-cp[0-9]+/include/python[0-9.]+#$py_inc#g" \
            -e "s#/opt/python/cp[0-9]+-cp[0-9]+/lib/python[0-9.]+/site-packages/numpy/_core/include#$np_inc#g"
}

_ftt_prefix_python() { # the interpreter seeing what is built into $prefix
    PYTHONPATH=$site${PYTHONPATH:+:$PYTHONPATH} LD_LIBRARY_PATH=$prefix/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH} \
        AMENT_PREFIX_PATH=$prefix:$FTT_VENV "$FTT_PY" "$@"
}

# A build is kept in the user's cache under the hash of its inputs, so a new
# checkout or virtualenv unpacks it in a second instead of building again.
_ftt_ros_cache() {
    printf '%s/ftt/ros-interfaces/%s-%s.tar' "${XDG_CACHE_HOME:-$HOME/.cache}" "$stamp" \
        "$(sha256sum "$FTT_ROOT/requirements.txt" | cut -c1-16)"
}

_ftt_ros_build() { # uses _ftt_ros_interfaces' locals: prefix, dirs, names, stamp
    local installed
    installed=$(mktemp)
    FTT_ROS_INSTALLED=$installed bash "$FTT_ROOT/scripts/build_interfaces.sh" "$prefix" "${dirs[@]}" ||
        ftt_die "building the ROS interfaces failed (see above)"
    for name in $names; do
        _ftt_prefix_python -c "import $name" || ftt_die "$name was built but does not import"
    done
    FTT_VENV=$prefix ftt_stamp_write ros-interfaces "$stamp"
    _ftt_ros_keep "$installed" || ftt_log "ROS interfaces: could not keep the build in $(_ftt_ros_cache)"
    rm -f "$installed"
    ftt_log "ROS interfaces built into $prefix: ${names//$'\n'/ }"
}

_ftt_ros_keep() { # FILE of installed paths -> the cache's tar (paths relative to prefix, the prefix beside)
    local cache list
    cache=$(_ftt_ros_cache)
    list=$(mktemp)
    mkdir -p "$(dirname "$cache")" || return 1
    sed -n "s#^$prefix/##p" "$1" | LC_ALL=C sort -u >"$list"
    printf '%s' "$prefix" >"$prefix/.ftt-ros-built-prefix"
    echo ".ftt-ros-built-prefix" >>"$list"
    tar -cf "$cache.part" -C "$prefix" -T "$list" && mv "$cache.part" "$cache"
    local status=$?
    rm -f "$list" "$prefix/.ftt-ros-built-prefix"
    return $status
}

_ftt_ros_restore() { # status 0 when the cache held this build and it imports from prefix
    local cache built file
    cache=$(_ftt_ros_cache)
    [ -f "$cache" ] || return 1
    mkdir -p "$prefix"
    tar -xf "$cache" -C "$prefix" || return 1
    built=$(cat "$prefix/.ftt-ros-built-prefix")
    rm -f "$prefix/.ftt-ros-built-prefix"
    # CMake exports and setup files name the prefix they were built into.
    if [ "$built" != "$prefix" ]; then
        tar -tf "$cache" | while read -r file; do
            [ -f "$prefix/$file" ] && grep -Iq -- "$built" "$prefix/$file" &&
                sed -i "s#$built#$prefix#g" "$prefix/$file"
        done
    fi
    for name in $names; do
        _ftt_prefix_python -c "import $name" >/dev/null 2>&1 || return 1
    done
    FTT_VENV=$prefix ftt_stamp_write ros-interfaces "$stamp"
    ftt_log "ROS interfaces unpacked from $cache into $prefix: ${names//$'\n'/ }"
}
_ftt_ros_interfaces
