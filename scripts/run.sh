#!/usr/bin/env bash
# README command 1: install what is missing (scripts/setup.sh), migrate the
# database (SpatiaLite in data/ftt.sqlite3 unless FTT_DATABASE_URL is set),
# make sure an administrator account exists, and serve FTT through Daphne's
# ASGI runserver (HTTP and websockets) on http://127.0.0.1:8000.
#
# Usage: bash scripts/run.sh [ADDRESS:PORT]     (default 127.0.0.1:8000)
set -euo pipefail
FTT_SCRIPT=run
# shellcheck source=scripts/lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"

address=${1:-127.0.0.1:8000}
bash "$FTT_ROOT/scripts/setup.sh"
cd "$FTT_ROOT"
export DJANGO_SETTINGS_MODULE=ftt_site.settings
py=$FTT_VENV/bin/python

ftt_phase "migrate"
"$py" manage.py migrate --noinput
ftt_phase "administrator account"
"$py" manage.py ftt_ensure_admin
ftt_phase_summary

# Reload on code changes only when debugging; a field laptop runs it as is.
reload=(--noreload)
FTT_DEBUG=${FTT_DEBUG:-0}
case "${FTT_DEBUG,,}" in 1 | true | yes | on) reload=() ;; esac
ftt_log "FTT at http://$address/ (Django admin at /admin/); Ctrl-C stops it"
exec "$py" manage.py runserver "${reload[@]}" "$address"
