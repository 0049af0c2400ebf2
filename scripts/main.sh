#!/usr/bin/env bash
# The main job: installs missing packages, builds, and runs the default job over the bundled
# scenes. Extra arguments go to the shadowlab command.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
scripts/build.sh
out=${SHADOWLAB_OUT:-out/main}
mkdir -p "$out"
for scene in $(./build/app/shadowlab scenes --names); do
  ./build/app/shadowlab reference "$scene" -o "$out/$scene" "$@"
done
echo "main: wrote the references under $out/"
