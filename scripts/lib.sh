# shellcheck shell=bash
# Helpers shared by scripts/setup.sh, run.sh and test.sh (and the hooks in
# scripts/setup.d/). Sourced, never executed. Each script sets FTT_SCRIPT to
# its own short name before logging.

FTT_ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
FTT_VENV=${FTT_VENV:-$FTT_ROOT/.venv}
FTT_SCRIPT=${FTT_SCRIPT:-ftt}
export FTT_ROOT FTT_VENV

# Microseconds since the epoch; EPOCHREALTIME may use a locale's decimal comma.
ftt_now_us() { printf '%s' "${EPOCHREALTIME//[!0-9]/}"; }

ftt_seconds() { # microseconds -> "12.3"
    local us=$1
    printf '%d.%d' $((us / 1000000)) $((us % 1000000 / 100000))
}

FTT_T0=$(ftt_now_us)

ftt_log() {
    printf '[%s %6ss] %s\n' "$FTT_SCRIPT" "$(ftt_seconds $(($(ftt_now_us) - FTT_T0)))" "$*"
}

ftt_die() {
    ftt_log "ERROR: $*" >&2
    exit 1
}

# Phases: ftt_phase NAME starts one (and ends the previous one); ftt_phase_end
# ends the current one. The durations are kept in FTT_PHASES for a summary.
FTT_PHASES=()
_ftt_phase_name=""
_ftt_phase_t=0

ftt_phase_end() {
    [ -n "$_ftt_phase_name" ] || return 0
    local took
    took=$(ftt_seconds $(($(ftt_now_us) - _ftt_phase_t)))
    FTT_PHASES+=("$(printf '%7ss  %s' "$took" "$_ftt_phase_name")")
    _ftt_phase_name=""
}

ftt_phase() {
    ftt_phase_end
    _ftt_phase_name=$1
    _ftt_phase_t=$(ftt_now_us)
    ftt_log "== $1"
}

ftt_phase_summary() {
    ftt_phase_end
    local line
    ftt_log "time per phase:"
    for line in "${FTT_PHASES[@]}"; do
        printf '    %s\n' "$line"
    done
}

# Runs a command as root: directly when we are root, else through sudo.
ftt_as_root() {
    if [ "$(id -u)" -eq 0 ]; then
        "$@"
    elif command -v sudo >/dev/null 2>&1; then
        sudo "$@"
    else
        ftt_die "need root or sudo to run: $*"
    fi
}

ftt_installed() { # PACKAGE -> status 0 when dpkg has it installed
    dpkg-query -W -f='${Status}' "$1" 2>/dev/null | grep -q 'install ok installed'
}

_ftt_apt_updated=0
ftt_apt_update_once() {
    [ "$_ftt_apt_updated" -eq 1 ] && return 0
    ftt_log "apt-get update"
    ftt_as_root env DEBIAN_FRONTEND=noninteractive apt-get update -qq
    _ftt_apt_updated=1
}

ftt_apt_candidate() { # PACKAGE -> status 0 when apt can install it
    local candidate
    candidate=$(apt-cache policy "$1" 2>/dev/null | awk '/Candidate:/ {print $2}')
    [ -n "$candidate" ] && [ "$candidate" != "(none)" ]
}

# ftt_apt_ensure "pkgA|pkgB" "pkgC" ...
# Each argument is one need, spelled as alternatives (Debian 12 and Ubuntu
# 24.04 name some libraries differently). A need is met when any alternative
# is installed; otherwise the first one apt offers gets installed.
ftt_apt_ensure() {
    local need alt alts missing=() chosen=() found
    for need in "$@"; do
        found=0
        IFS='|' read -ra alts <<<"$need"
        for alt in "${alts[@]}"; do
            if ftt_installed "$alt"; then
                found=1
                break
            fi
        done
        [ "$found" -eq 1 ] || missing+=("$need")
    done
    if [ "${#missing[@]}" -eq 0 ]; then
        return 0
    fi
    command -v apt-get >/dev/null 2>&1 || ftt_die "missing packages (${missing[*]}) and no apt-get"
    ftt_apt_update_once
    for need in "${missing[@]}"; do
        found=0
        IFS='|' read -ra alts <<<"$need"
        for alt in "${alts[@]}"; do
            if ftt_apt_candidate "$alt"; then
                chosen+=("$alt")
                found=1
                break
            fi
        done
        [ "$found" -eq 1 ] || ftt_die "no apt package for: ${need//|/ or }"
    done
    ftt_log "apt-get install ${chosen[*]}"
    ftt_as_root env DEBIAN_FRONTEND=noninteractive \
        apt-get install -y -qq -o Dpkg::Use-Pty=0 --no-install-recommends "${chosen[@]}"
}

# PostgreSQL major version to use: the newest installed server that has
# PostGIS, else the newest installed server, else empty.
ftt_pg_major() {
    local dir ver best="" best_postgis=""
    for dir in /usr/lib/postgresql/*/bin/postgres; do
        [ -x "$dir" ] || continue
        ver=${dir#/usr/lib/postgresql/}
        ver=${ver%%/*}
        if [ -z "$best" ] || [ "$ver" -gt "$best" ]; then best=$ver; fi
        if [ -e "/usr/share/postgresql/$ver/extension/postgis.control" ]; then
            if [ -z "$best_postgis" ] || [ "$ver" -gt "$best_postgis" ]; then best_postgis=$ver; fi
        fi
    done
    printf '%s' "${best_postgis:-$best}"
}

# uv installs the locks: pip takes minutes for them on a fresh machine, uv
# downloads in parallel and links from its cache (~/.cache/uv) afterwards. It
# reads PyPI; UV_INDEX_URL or UV_DEFAULT_INDEX point it at a mirror.
ftt_uv_ensure() { # installs the locked uv into the virtualenv unless it is there
    local want
    want=$(sed -n 's/^uv==\([^ ]*\).*/\1/p' "$FTT_ROOT/requirements-uv.txt")
    if [ "$("$FTT_VENV/bin/uv" --version 2>/dev/null | cut -d' ' -f2)" != "$want" ]; then
        ftt_log "pip install uv $want"
        "$FTT_PY" -m pip install -q --disable-pip-version-check --require-hashes \
            -r "$FTT_ROOT/requirements-uv.txt"
    fi
}
ftt_uv_install() { # ARGS... -> uv pip install --require-hashes ARGS into the virtualenv
    # Bytecode now: processes started with PYTHONDONTWRITEBYTECODE would compile
    # every module they import, every time.
    "$FTT_VENV/bin/uv" pip install --quiet --compile-bytecode --python "$FTT_PY" --require-hashes "$@"
}

# Stamp files let a step skip work whose inputs have not changed.
# ftt_stamp_ok NAME VALUE: status 0 when the stamp NAME holds VALUE.
ftt_stamp_ok() { [ -f "$FTT_VENV/.ftt-stamp-$1" ] && [ "$(cat "$FTT_VENV/.ftt-stamp-$1")" = "$2" ]; }
ftt_stamp_write() { printf '%s' "$2" >"$FTT_VENV/.ftt-stamp-$1"; }

# Prints the first Chromium on PATH that really starts. On Ubuntu 24.04 the
# apt package "chromium-browser" is a stub that only asks for the snap.
ftt_working_chromium() {
    local name path
    for name in chromium chromium-browser; do
        path=$(command -v "$name") || continue
        if timeout 30 "$path" --headless --no-sandbox --version >/dev/null 2>&1; then
            printf '%s\n' "$path"
            return 0
        fi
    done
    return 1
}
