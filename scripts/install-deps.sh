#!/usr/bin/env bash
# Installs the Debian 12 packages shadowlab builds and tests with, only those missing.
# Usage: scripts/install-deps.sh   (python3 runs the report's charts, which need no package of their own;
# scenes/data/make_assets.py, which regenerates bundled assets and is never run by the build or the
# tests, also needs python3-numpy and python3-pil)
set -euo pipefail
pkgs=(build-essential cmake pkg-config libembree-dev libglm-dev libopenimageio-dev libopenexr-dev libpng-dev libtinyobjloader-dev libtinygltf-dev
      mesa-vulkan-drivers libvulkan-dev glslang-dev glslang-tools spirv-tools vulkan-validationlayers
      nlohmann-json3-dev libcli11-dev libtbb-dev libgtest-dev libbenchmark-dev
      python3 chromium
      clang libclang-rt-14-dev
      slurm-wlm munge     # the loopback Slurm test (tests/slurm_loopback_test.sh, scripts/slurm-local.sh)
      assimp-testmodels)  # test data only: real OBJ and glTF files, good and malformed, that nobody here wrote
missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}\n' "$p" 2>/dev/null | grep -q '^install ok installed' || missing+=("$p")
done
# Node.js and npm run the three.js adapter's driver (adapters/three): Debian's nodejs and npm where no
# node is installed; a node from elsewhere (18 or newer) is kept as it is.
command -v node >/dev/null 2>&1 && command -v npm >/dev/null 2>&1 || missing+=(nodejs npm)
if [ ${#missing[@]} -gt 0 ]; then
  echo "install-deps: installing ${missing[*]}"
  sudo_cmd=()
  [ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
  export DEBIAN_FRONTEND=noninteractive
  "${sudo_cmd[@]}" apt-get update -qq
  "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
# The adapters' npm packages (three.js), exactly as their lock files pin them, only when missing or
# older than the lock file.
here="$(cd "$(dirname "$0")/.." && pwd)"
for lock in "$here"/adapters/*/package-lock.json; do
  [ -f "$lock" ] || continue
  dir=$(dirname "$lock")
  if [ ! -f "$dir/node_modules/.package-lock.json" ] || [ "$lock" -nt "$dir/node_modules/.package-lock.json" ]; then
    echo "install-deps: npm ci in ${dir#"$here"/}"
    (cd "$dir" && npm ci --no-audit --no-fund --loglevel=error)
  fi
done
