#!/usr/bin/env bash
# Collects every translatable string of FTT into the German catalogues, in one step:
#   bash scripts/messages.sh
# then translate each new or "fuzzy" entry of locale/de/LC_MESSAGES/django.po
# (Python, templates, the report) and djangojs.po (static/gui), and run the check
#   bash scripts/test.sh tests/test_translations.py
# scripts/setup.sh compiles the .po files to .mo (scripts/setup.d/45-translations.sh).
set -euo pipefail
FTT_SCRIPT="messages"
# shellcheck source=scripts/lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
cd "$FTT_ROOT"
export DJANGO_SETTINGS_MODULE=ftt_site.settings
# The folders makemessages must not read: installed and generated files, tests.
ignore=(--ignore=.venv --ignore=node_modules --ignore=data --ignore=tests --ignore=tmp
    --ignore=benchmarks --ignore=test-artifacts --ignore=eslint.config.js)
"$FTT_VENV/bin/python" manage.py makemessages -l de -d django --no-obsolete "${ignore[@]}"
"$FTT_VENV/bin/python" manage.py makemessages -l de -d djangojs --no-obsolete "${ignore[@]}"
ftt_log "updated locale/de/LC_MESSAGES/django.po and djangojs.po; translate the new entries"
