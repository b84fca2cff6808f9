#!/usr/bin/env bash
# Installs whatever FTT needs and does not have yet, on Debian 12 or Ubuntu
# 24.04 (as root, or a user with sudo):
#   1. system packages (GDAL, GEOS, PROJ, SpatiaLite; with --test also
#      PostgreSQL+PostGIS, Redis, Chromium, poppler-utils);
#   2. the virtualenv .venv (python3 >= 3.11, or FTT_PYTHON) with the
#      locked requirements (requirements.txt, with --test requirements-dev.txt;
#      every file's hash checked), installed by uv (requirements-uv.txt, put
#      in with pip), skipped while the lock matches the stamp in .venv;
#   3. the hooks scripts/setup.d/*.sh, sourced in name order.
# A second run only checks, in about a second.
#
# Usage: bash scripts/setup.sh [--test]
set -euo pipefail
FTT_SCRIPT=setup
# shellcheck source=scripts/lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"

FTT_SETUP_MODE=run
case "${1:-}" in
"") ;;
--test) FTT_SETUP_MODE="test" ;;
*)
    echo "usage: bash scripts/setup.sh [--test]" >&2
    exit 2
    ;;
esac
export FTT_SETUP_MODE
# Relative paths given to the hooks (FTT_ROS_INTERFACES) are relative to here.
export FTT_CALLER_DIR=$PWD
cd "$FTT_ROOT"

python_ok() { # INTERPRETER -> status 0 when it is >= 3.11 and can make venvs
    "$1" -c 'import ensurepip, sys, venv; sys.exit(sys.version_info < (3, 11))' >/dev/null 2>&1
}

venv_ok() {
    [ -x "$FTT_VENV/bin/python" ] &&
        "$FTT_VENV/bin/python" -c 'import sys; sys.exit(sys.version_info < (3, 11))' >/dev/null 2>&1
}

# --- 1. system packages -----------------------------------------------------
ftt_phase "system packages"
needs=(
    "libgdal32|libgdal34t64|libgdal36"
    "libgeos-c1v5|libgeos-c1t64"
    "libproj25"
    "libsqlite3-mod-spatialite"
    # python-ldap (directory sign-in) is built from source against these.
    "libldap2-dev"
    "libsasl2-dev"
)
base_python=${FTT_PYTHON:-python3}
if ! venv_ok && ! python_ok "$base_python"; then
    needs+=("python3" "python3-venv")
fi
if [ "$FTT_SETUP_MODE" = test ]; then
    needs+=("redis-server" "chromium|chromium-browser" "poppler-utils" "shellcheck" "slapd")
    # A configured database needs no local server.
    if [ -z "${FTT_DATABASE_URL:-}" ]; then
        pg=$(ftt_pg_major)
        if [ -z "$pg" ]; then
            # No server yet: take the distribution's default major version.
            ftt_apt_update_once
            pg=$(apt-cache depends postgresql 2>/dev/null |
                sed -n 's/^ *Depends: postgresql-\([0-9][0-9]*\)$/\1/p' | head -n 1)
            [ -n "$pg" ] || ftt_die "cannot tell which PostgreSQL version apt offers"
        fi
        needs+=("postgresql-$pg-postgis-3")
    fi
fi
ftt_apt_ensure "${needs[@]}"

# --- 2. virtualenv and requirements ------------------------------------------
ftt_phase "virtualenv"
if ! venv_ok; then
    if python_ok "$base_python"; then
        py=$base_python
    elif python_ok /usr/bin/python3; then
        py=/usr/bin/python3
    else
        ftt_die "need Python >= 3.11 with venv; set FTT_PYTHON to one"
    fi
    ftt_log "creating $FTT_VENV with $("$py" -V 2>&1)"
    "$py" -m venv --clear "$FTT_VENV"
fi
export FTT_PY=$FTT_VENV/bin/python
ftt_log "$("$FTT_PY" -V 2>&1) in $FTT_VENV"

# The locks come from requirements*.in (scripts/lock.sh writes them).
requirements_hash() { # FILE... -> hash of the files and the interpreter
    { "$FTT_PY" -VV && cat "$@"; } | sha256sum | cut -d' ' -f1
}
hash_run=$(requirements_hash requirements.txt)
hash_test=$(requirements_hash requirements.txt requirements-dev.txt)
if [ "$FTT_SETUP_MODE" = test ]; then
    file=requirements-dev.txt
    up_to_date() { ftt_stamp_ok pip-test "$hash_test"; }
else
    file=requirements.txt
    # The test lock includes the runtime lock.
    up_to_date() { ftt_stamp_ok pip-run "$hash_run" || ftt_stamp_ok pip-test "$hash_test"; }
fi
if up_to_date; then
    ftt_log "$file: already installed"
else
    ftt_uv_ensure
    ftt_log "uv pip install --require-hashes -r $file"
    ftt_uv_install -r "$file"
    "$FTT_PY" -m pip check
    ftt_stamp_write pip-run "$hash_run"
    if [ "$FTT_SETUP_MODE" = test ]; then
        ftt_stamp_write pip-test "$hash_test"
    fi
fi

# --- 3. hooks ------------------------------------------------------------------
# Each hook is sourced with this script's variables and helpers (FTT_ROOT,
# FTT_VENV, FTT_PY, FTT_SETUP_MODE, ftt_apt_ensure, ftt_stamp_ok, ...) and must
# itself skip work that is already done.
shopt -s nullglob
for hook in "$FTT_ROOT"/scripts/setup.d/*.sh; do
    ftt_phase "hook ${hook##*/}"
    # shellcheck source=/dev/null
    source "$hook"
done
shopt -u nullglob

# A run that had work to do shows where its time went.
if [ $(($(ftt_now_us) - FTT_T0)) -gt 3000000 ]; then
    ftt_phase_summary
else
    ftt_phase_end
fi
ftt_log "setup done ($FTT_SETUP_MODE)"
