#!/usr/bin/env bash
# Regenerates tests/golden/baseline.json with the real pipeline: one sweep per *.sweep.json here,
# then `shadowlab gate --update-baseline`, which prints every metric that changed; likewise
# tests/golden/stability_baseline.json from the stability run in stability.args. Run it only on
# purpose (a change that moves metrics intentionally), review the printed diff and `git diff`,
# and commit the new baseline with the change that caused it.
#
#   tests/golden/update.sh [path/to/shadowlab]      (default: build/app/shadowlab)
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
bin="${1:-$root/build/app/shadowlab}"
if [[ ! -x "$bin" ]]; then
  echo "update.sh: error: $bin is not an executable; build first (scripts/build.sh) or pass its path" >&2
  exit 2
fi
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
currents=()
for sweep in "$here"/*.sweep.json; do
  name="$(basename "$sweep" .sweep.json)"
  "$bin" sweep --sweep "$sweep" -o "$work/$name" --cache "$work/cache" --no-report >/dev/null
  currents+=("$work/$name/results.json")
done
"$bin" gate "${currents[@]}" --baseline "$here/baseline.json" --update-baseline
# The golden stability run (its own baseline): the arguments in stability.args, comments dropped.
read -r -a stability_args <<< "$(grep -v '^#' "$here/stability.args" | tr '\n' ' ')"
"$bin" stability "${stability_args[@]}" -o "$work/stability" --cache "$work/cache" >/dev/null
"$bin" gate "$work/stability/stability.json" --baseline "$here/stability_baseline.json" --update-baseline
