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
if [ ${#missing[@]} -eq 0 ]; then exit 0; fi
echo "install-deps: installing ${missing[*]}"
sudo_cmd=()
[ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -qq
"${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
