#!/usr/bin/env bash
# The main job: installs missing packages, builds, and runs the default sweep
# (compare/report/default_sweep.json) over every bundled scene, ending in a report.
# Extra arguments go to `shadowlab sweep` (e.g. --grid map.size=256,1024 or scene names).
# Running it again continues an interrupted sweep; delete the output folder to start over.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
scripts/build.sh
out=${SHADOWLAB_OUT:-out/main}
./build/app/shadowlab sweep --sweep compare/report/default_sweep.json -o "$out" "$@"
echo "main: open $(cd "$out" && pwd)/report.html in a browser (it works from disk, no network)"
