#!/usr/bin/env bash
# A live test within a minute, without a robot: sets FTT up like
# scripts/run.sh, starts a simulated robot (ftt_simulate) and the collector
# (ftt_collect) for the vehicle "sim" in the background, then serves the GUI.
# Ctrl-C stops all three.
#
# Usage: bash scripts/demo.sh [ADDRESS:PORT]
set -euo pipefail
FTT_SCRIPT=demo
# shellcheck source=scripts/lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"

bash "$FTT_ROOT/scripts/setup.sh"
cd "$FTT_ROOT"
py=$FTT_VENV/bin/python
"$py" manage.py migrate --noinput
# ROS traffic stays on this machine unless the caller says otherwise.
export ROS_AUTOMATIC_DISCOVERY_RANGE=${ROS_AUTOMATIC_DISCOVERY_RANGE:-LOCALHOST}
logs=${FTT_DATA_DIR:-$FTT_ROOT/data}
mkdir -p "$logs"
"$py" manage.py ftt_simulate --open-leg sim >"$logs/demo-robot.log" 2>&1 &
robot=$!
"$py" manage.py ftt_collect --vehicle sim --start-logging >"$logs/demo-collector.log" 2>&1 &
collector=$!
trap 'kill -TERM "$robot" "$collector" 2>/dev/null; wait "$robot" "$collector" 2>/dev/null' EXIT
ftt_log "simulated robot (pid $robot) and collector (pid $collector) log into vehicle 'sim';"
ftt_log "their output is in $logs/demo-robot.log and $logs/demo-collector.log"
bash "$FTT_ROOT/scripts/run.sh" "$@"
