#!/usr/bin/env bash
# README command 2: install what is missing (scripts/setup.sh --test), bring
# up PostgreSQL+PostGIS on loopback unless FTT_DATABASE_URL names a database,
# make sure Redis answers, lint, and run the test suite:
#   (lint: ruff, the import layers of pyproject.toml, ESLint for static/gui,
#    and the shell linter over the scripts)
#   a) everything but tests/e2e on PostGIS, spread over xdist workers (the
#      tests marked `serial` in one process of their own, beside b and c);
#   b) the tests marked `spatialite` (the code under them differs between the
#      databases, or they drive the embedded database) on SpatiaLite, side by
#      side with
#   c) the browser tests in tests/e2e, in a pytest process of their own.
# Exits non-zero when any step fails; the last lines give each phase's time
# and its slowest tests.
#
# Usage: bash scripts/test.sh [PYTEST ARGS...]
#   With arguments only one pytest run happens, with those arguments, after
#   setup and services (no lint). Without a path among them it covers tests/
#   minus tests/e2e. FTT_TEST_SPATIALITE=1 makes it run on SpatiaLite.
#   FTT_TEST_WORKERS sets the xdist workers of the full run (default: one
#   more than the cores; 0 runs in one process).
#   Examples: bash scripts/test.sh -k segment -x
#             bash scripts/test.sh -n 2 tests/events
#             bash scripts/test.sh tests/e2e/test_live_map.py
set -euo pipefail
FTT_SCRIPT="test"
# shellcheck source=scripts/lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
cd "$FTT_ROOT"

ftt_phase "setup"
bash scripts/setup.sh --test
py=$FTT_VENV/bin/python

export DJANGO_SETTINGS_MODULE=ftt_site.settings
# ROS 2: stay on this host, on a domain of our own, with the only RMW the PyPI
# wheels have. Each xdist worker takes the next domain (tests/support/workers.py);
# 0-101 keeps the DDS ports below the ephemeral range, so the base stays <= 92.
export ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST
# FTT_ROS_DOMAIN_ID pins it when several suites share a machine.
export ROS_DOMAIN_ID=${FTT_ROS_DOMAIN_ID:-$((10 + $$ % 83))}
unset RMW_IMPLEMENTATION ROS_LOCALHOST_ONLY

as_postgres() { # run a command as the postgres user, from a directory it can read
    if [ "$(id -u)" -eq 0 ]; then
        (cd / && runuser -u postgres -- "$@")
    else
        (cd / && sudo -u postgres "$@")
    fi
}

# Starts the local cluster (main, or FTT_PG_CLUSTER), creating it if missing,
# and makes role ftt (SUPERUSER, because Django creates the untrusted postgis
# extension in the test database) and database ftt with PostGIS. Exports
# FTT_DATABASE_URL.
start_postgis() {
    local ver port status cluster=${FTT_PG_CLUSTER:-main}
    ver=$(ftt_pg_major)
    [ -n "$ver" ] || ftt_die "no PostgreSQL server installed"
    cluster_port_status() {
        pg_lsclusters -h | awk -v v="$ver" -v c="$cluster" '$1 == v && $2 == c {print $3, $4}'
    }
    read -r port status < <(cluster_port_status) || true
    if [ -z "${port:-}" ]; then
        ftt_log "creating PostgreSQL $ver cluster $cluster"
        ftt_as_root pg_createcluster "$ver" "$cluster" >/dev/null
        read -r port status < <(cluster_port_status)
    fi
    if [[ $status != online* ]]; then
        ftt_log "starting PostgreSQL $ver $cluster on port $port"
        ftt_as_root pg_ctlcluster "$ver" "$cluster" start
    fi
    local tries=0
    until pg_isready -q -h 127.0.0.1 -p "$port"; do
        tries=$((tries + 1))
        [ "$tries" -le 100 ] || ftt_die "PostgreSQL on port $port did not come up"
        sleep 0.2
    done
    as_postgres psql -X -q -v ON_ERROR_STOP=1 -p "$port" -d postgres <<'SQL'
SELECT 'CREATE ROLE ftt' WHERE NOT EXISTS (SELECT FROM pg_roles WHERE rolname = 'ftt')\gexec
ALTER ROLE ftt LOGIN SUPERUSER PASSWORD 'ftt';
SELECT 'CREATE DATABASE ftt OWNER ftt'
  WHERE NOT EXISTS (SELECT FROM pg_database WHERE datname = 'ftt')\gexec
\c ftt
CREATE EXTENSION IF NOT EXISTS postgis;
SQL
    export FTT_DATABASE_URL="postgis://ftt:ftt@127.0.0.1:$port/ftt"
    ftt_log "PostGIS $(PGPASSWORD=ftt psql -X -At -h 127.0.0.1 -p "$port" -U ftt -d ftt \
        -c 'SELECT postgis_lib_version()') in PostgreSQL $ver $cluster on port $port"
}

# Uses the Redis on 127.0.0.1:6379, starting one there when none answers.
start_redis() {
    if [ -n "${FTT_TEST_REDIS_URL:-}" ]; then
        ftt_log "Redis from FTT_TEST_REDIS_URL"
        return 0
    fi
    if ! redis-cli -h 127.0.0.1 -p 6379 ping >/dev/null 2>&1; then
        ftt_log "starting redis-server on 127.0.0.1:6379"
        mkdir -p data
        redis-server --port 6379 --bind 127.0.0.1 --daemonize yes --save '' --appendonly no \
            --dir "$FTT_ROOT/data" --pidfile "$FTT_ROOT/data/redis.pid" \
            --logfile "$FTT_ROOT/data/redis.log"
        local tries=0
        until redis-cli -h 127.0.0.1 -p 6379 ping >/dev/null 2>&1; do
            tries=$((tries + 1))
            [ "$tries" -le 50 ] || ftt_die "redis-server did not answer"
            sleep 0.1
        done
    fi
    export FTT_TEST_REDIS_URL=redis://127.0.0.1:6379/0
}

ftt_phase "database and redis"
if [ -n "${FTT_DATABASE_URL:-}" ]; then
    ftt_log "using FTT_DATABASE_URL from the environment"
elif [ "${FTT_TEST_SPATIALITE:-0}" != 1 ]; then
    start_postgis
fi
start_redis

failed=()
# step [--may-be-empty] NAME COMMAND...: runs one check and records a failure
# instead of stopping. With --may-be-empty, pytest's exit code 5 (no test
# collected or selected) is a pass.
step() {
    local may_be_empty=0 rc=0 name
    if [ "$1" = --may-be-empty ]; then
        may_be_empty=1
        shift
    fi
    name=$1
    shift
    ftt_phase "$name"
    "$@" || rc=$?
    if [ "$rc" -eq 5 ] && [ "$may_be_empty" -eq 1 ]; then
        ftt_log "$name: no tests selected"
    elif [ "$rc" -ne 0 ]; then
        failed+=("$name (exit $rc)")
        ftt_log "FAILED: $name (exit $rc)"
    fi
}

# Phases that run side by side: each writes its output to a log of its own,
# which is shown when it ends; its time and failure are recorded as step's.
declare -A together_pid=() together_t0=()
together_names=()
# Short: sockets made below a test's tmp_path have at most 107 bytes of path.
logs=$(mktemp -d "${TMPDIR:-/tmp}/ftt-XXXX")
start_together() { # NAME COMMAND...
    local name=$1
    shift
    ftt_log "== $name (started beside the next phase)"
    together_names+=("$name")
    together_t0[$name]=$(ftt_now_us)
    "$@" >"$logs/${name//[^A-Za-z0-9]/_}.log" 2>&1 &
    together_pid[$name]=$!
}
finish_together() { # waits for every phase start_together started
    local name rc took
    for name in "${together_names[@]}"; do
        rc=0
        wait "${together_pid[$name]}" || rc=$?
        took=$(ftt_seconds $(($(ftt_now_us) - together_t0[$name])))
        ftt_log "== $name (ended after ${took}s, its output:)"
        cat "$logs/${name//[^A-Za-z0-9]/_}.log"
        FTT_PHASES+=("$(printf '%7ss  %s (side by side)' "$took" "$name")")
        if [ "$rc" -eq 5 ]; then
            ftt_log "$name: no tests selected"
        elif [ "$rc" -ne 0 ]; then
            failed+=("$name (exit $rc)")
            ftt_log "FAILED: $name (exit $rc)"
        fi
    done
    together_names=()
}

pytest=("$py" -m pytest)

finish() {
    # Fast DDS leaves shared-memory segments behind when a process is killed.
    "$FTT_VENV/bin/fastdds" shm clean >/dev/null 2>&1 || true
    ftt_phase_summary
    "$py" scripts/slowest_tests.py --top 10 "$logs"/*.xml || true
    rm -rf "$logs"
    if [ "${#failed[@]}" -gt 0 ]; then
        ftt_log "FAILED:"
        printf '    %s\n' "${failed[@]}"
        exit 1
    fi
    ftt_log "all passed"
}

if [ "$#" -gt 0 ]; then
    has_path=0
    browser=0
    for arg in "$@"; do
        case "$arg" in -*) continue ;; esac
        if [ -e "${arg%%::*}" ]; then
            has_path=1
            case "$arg" in tests/e2e*) browser=1 ;; esac
        fi
    done
    args=()
    [ "$browser" -eq 1 ] || args+=(-p no:playwright)
    [ "$has_path" -eq 1 ] || args+=(tests --ignore=tests/e2e)
    if [ "${FTT_TEST_SPATIALITE:-0}" = 1 ]; then
        step "pytest $* (SpatiaLite)" env -u FTT_DATABASE_URL "${pytest[@]}" "${args[@]}" "$@"
    else
        step "pytest $*" "${pytest[@]}" "${args[@]}" "$@"
    fi
    finish
    exit 0
fi

step "ruff check" "$FTT_VENV/bin/ruff" check .
step "ruff format --check" "$FTT_VENV/bin/ruff" format --check .
step "import layers (lint-imports)" "$FTT_VENV/bin/lint-imports"
step "eslint static/gui" npx --no-install eslint static/gui
scripts=(scripts/*.sh scripts/setup.d/*.sh .ci/run)
step "shellcheck scripts" shellcheck -x --shell=bash --severity=warning "${scripts[@]}"

workers=${FTT_TEST_WORKERS:-$(($(nproc) + 1))}
spread=()
[ "$workers" -eq 0 ] || spread=(-n "$workers" --dist loadfile)
# Each run its own JUnit file and temporary folder: the runs side by side must
# not clear each other's.
pg_files=("--junitxml=$logs/pg.xml" "--basetemp=$logs/pg")
sl_files=("--junitxml=$logs/sl.xml" "--basetemp=$logs/sl")
e2e_files=("--junitxml=$logs/e2e.xml" "--basetemp=$logs/e2e")
serial_files=("--junitxml=$logs/serial.xml" "--basetemp=$logs/serial")

if [ -n "${FTT_DATABASE_URL:-}" ]; then
    step "pytest on PostGIS" "${pytest[@]}" -p no:playwright "${spread[@]}" "${pg_files[@]}" \
        -m "not serial" tests --ignore=tests/e2e
    start_together "pytest on PostGIS, tests marked serial (one process)" "${pytest[@]}" \
        -p no:playwright -p no:xdist "${serial_files[@]}" -m serial tests --ignore=tests/e2e
    # The same code on the embedded database only where it differs from PostGIS.
    start_together "pytest on SpatiaLite (marked spatialite)" env -u FTT_DATABASE_URL \
        "${pytest[@]}" -p no:playwright "${spread[@]}" "${sl_files[@]}" \
        -m "spatialite and not postgis_only" tests --ignore=tests/e2e
else
    step "pytest on SpatiaLite (FTT_TEST_SPATIALITE=1)" "${pytest[@]}" -p no:playwright \
        "${spread[@]}" "${sl_files[@]}" tests --ignore=tests/e2e -m "not postgis_only and not serial"
    start_together "pytest on SpatiaLite, tests marked serial (one process)" "${pytest[@]}" \
        -p no:playwright -p no:xdist "${serial_files[@]}" -m "serial and not postgis_only" \
        tests --ignore=tests/e2e
fi

if [ -d tests/e2e ]; then
    # Browser tests need their own process: Playwright's sync API keeps an
    # event loop running in the test thread, which pytest-asyncio's tests
    # cannot share.
    # Past the ROS domains and Redis databases of the run beside it.
    beside=$((workers > 0 ? workers : 1))
    redis_db=${FTT_TEST_REDIS_URL##*/}
    step --may-be-empty "pytest e2e (browser)" env FTT_ROS_DOMAIN_ID=$((ROS_DOMAIN_ID + beside)) \
        FTT_TEST_REDIS_URL="${FTT_TEST_REDIS_URL%/*}/$((redis_db + beside))" \
        "${pytest[@]}" "${e2e_files[@]}" tests/e2e
fi
finish_together

finish
