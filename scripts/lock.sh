#!/usr/bin/env bash
# Writes the hashed locks from their sources, for `pip install --require-hashes`:
#   requirements.in        -> requirements.txt        (runtime; scripts/setup.sh)
#   requirements-dev.in    -> requirements-dev.txt    (runtime + test tools; setup.sh --test)
#   requirements-rosidl.in -> requirements-rosidl.txt (scripts/setup.d/50-ros-interfaces.sh)
#   requirements-uv.in     -> requirements-uv.txt     (the installer setup.sh installs first)
# The test and build locks keep the runtime lock's versions. A version already
# locked stays while the sources allow it; `--upgrade` or `--upgrade-package
# NAME` (passed on to uv) takes newer ones. The locks hold every platform
# (markers keep the x86_64-only ROS wheels to x86_64) and Python 3.11 and
# newer, resolved from PyPI alone, whatever local wheel folders pip is set up
# to read on this machine.
#
# Usage: bash scripts/lock.sh [uv pip compile options]   (needs setup.sh --test)
set -euo pipefail
FTT_SCRIPT=lock
# shellcheck source=scripts/lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
cd "$FTT_ROOT"

uv=${FTT_UV:-$FTT_VENV/bin/uv}
[ -x "$uv" ] || ftt_die "no $uv: run bash scripts/setup.sh --test first"
for name in requirements requirements-dev requirements-rosidl requirements-uv; do
    ftt_log "$name.in -> $name.txt"
    "$uv" pip compile --quiet --universal --python-version 3.11 --generate-hashes \
        --no-annotate --custom-compile-command "bash scripts/lock.sh" \
        --default-index https://pypi.org/simple "$@" -o "$name.txt" "$name.in"
done
