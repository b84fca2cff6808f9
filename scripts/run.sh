#!/usr/bin/env bash
# README command 1: install what is missing (scripts/setup.sh), migrate the
# database if a migration is missing (SpatiaLite in data/ftt.sqlite3 unless
# FTT_DATABASE_URL is set), make sure an administrator account exists
# (manage.py ftt_prepare), and serve FTT (HTTP and
# websockets) on http://127.0.0.1:8000 with the production server: Gunicorn
# supervising Uvicorn workers (ftt_site/server/gunicorn.conf.py; README, Production),
# and beside it the job worker that makes requested reports and imports
# (manage.py ftt_worker); Ctrl-C stops both, at once when idle, else after
# the requests in flight and the job at hand.
#
# Usage: bash scripts/run.sh [ADDRESS:PORT]     (default 127.0.0.1:8000)
set -euo pipefail
# Everything the server writes (database, secret key, media, reports) is for
# FTT's user only; other local users read nothing.
umask 077
FTT_SCRIPT=run
# shellcheck source=scripts/lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"

address=${1:-127.0.0.1:8000}
bash "$FTT_ROOT/scripts/setup.sh"
cd "$FTT_ROOT"
export DJANGO_SETTINGS_MODULE=ftt_site.settings
py=$FTT_VENV/bin/python

# One process for the system checks, the migrations still missing (none on a
# restart) and the administrator account: each manage.py command loads Django
# and checks everything again (README, Quick start: start-up figures).
ftt_phase "checks, migrations, administrator account"
"$py" manage.py ftt_prepare
ftt_phase_summary

# Reload on code changes only when debugging; a field laptop runs it as is.
reload=()
FTT_DEBUG=${FTT_DEBUG:-0}
case "${FTT_DEBUG,,}" in 1 | true | yes | on) reload=(--reload) ;; esac
# One process suits the embedded database on a laptop; a server sets more.
export FTT_WEB_WORKERS=${FTT_WEB_WORKERS:-1}
# Requested reports and imports are jobs in the database; this worker runs
# them. A job it was running when stopped the hard way is retried by the next.
# It runs in a session of its own so that Ctrl-C reaches it once, from here:
# a second signal makes it abandon the job at hand.
# ftt_prepare has just run the system checks.
setsid "$py" manage.py ftt_worker --verbosity 0 --skip-checks &
worker=$!
web=""
stopping=0
stop() { # Ctrl-C or SIGTERM: both stop together, each once
    [ "$stopping" -eq 0 ] || return 0
    stopping=1
    kill -TERM "$worker" ${web:+"$web"} 2>/dev/null || true
}
trap stop INT TERM
trap 'stop; wait' EXIT
ftt_log "FTT at http://$address/ (Django admin at /admin/); Ctrl-C stops it"
# The script, not `python -m gunicorn`: its master can start a successor on
# `kill -USR2` (README, Production: restarts and upgrades).
"$FTT_VENV/bin/gunicorn" -c ftt_site/server/gunicorn.conf.py "${reload[@]}" --bind "$address" \
    ftt_site.asgi:application &
web=$!
status=0
wait "$web" || status=$?
if [ "$stopping" -eq 1 ]; then
    # The signal ended the wait; the server finishes what is in flight.
    status=0
    wait "$web" || status=$?
fi
exit "$status"
