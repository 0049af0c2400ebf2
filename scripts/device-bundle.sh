#!/usr/bin/env bash
# Packs shadowlab for a bare machine (a GPU box with no Debian packages of ours): the binary built
# with SHADOWLAB_IMAGE_IO=exr-png (OpenEXR + libpng instead of OpenImageIO and its ~390 MB of
# dependencies) into build-device/, every shared library it needs except glibc's own, the data it
# reads at run time (scenes/data, compare/report), scripts/gpu-check.sh and a launcher, as one
# xz tarball: .device-bundle/shadowlab-device.tar.xz (git-ignored).
#
# Usage: scripts/device-bundle.sh [--check]
#   --check  also unpack the tarball into a temporary folder and run it through its launcher here
#            (shadowlab scenes, devices, run grazing on lavapipe) and check with ldd that every
#            library resolves inside the bundle or to glibc.
# On the other machine:  tar -xJf shadowlab-device.tar.xz && shadowlab/shadowlab devices
# (README.md, "On a real GPU"). The tarball must stay under 48 MiB (the device tool carries 64 MiB
# in all, the repository included): larger, this script refuses and removes it.
set -euo pipefail
cd "$(dirname "$0")/.."
check=0
for a in "$@"; do
  case "$a" in
    --check) check=1 ;;
    *) echo "device-bundle: error: unknown argument \"$a\"; expected --check or nothing" >&2; exit 2 ;;
  esac
done
limit_bytes=$((48 * 1024 * 1024))
out=.device-bundle
stage=$out/shadowlab
tarball=$out/shadowlab-device.tar.xz

scripts/install-deps.sh
jobs=${SHADOWLAB_JOBS:-$(nproc 2>/dev/null || echo 2)}
cmake -S . -B build-device -DCMAKE_BUILD_TYPE=Release -DSHADOWLAB_IMAGE_IO=exr-png >/dev/null
cmake --build build-device -j"$jobs" --target shadowlab
binary=build-device/app/shadowlab

rm -rf "$stage" "$tarball"
mkdir -p "$stage/bin" "$stage/lib" "$stage/scenes" "$stage/compare" "$stage/scripts"
cp "$binary" "$stage/bin/shadowlab"
strip --strip-unneeded "$stage/bin/shadowlab"

# glibc's own libraries are on every Linux machine and must match its kernel interface: never
# bundled. Everything else ldd resolves is copied under its soname (the name the binary asks for).
is_glibc() {
  case "$1" in
    linux-vdso.so.*|libc.so.*|libm.so.*|libdl.so.*|libpthread.so.*|librt.so.*|libresolv.so.*|ld-linux*.so.*) return 0 ;;
    *) return 1 ;;
  esac
}
ldd "$binary" | while read -r name arrow path _; do
  [ "$arrow" = "=>" ] || continue
  is_glibc "$name" && continue
  if [ "$path" = "not" ]; then echo "device-bundle: error: $binary needs $name, which is not installed here" >&2; exit 3; fi
  cp -L "$path" "$stage/lib/$name"
done
cp -r scenes/data "$stage/scenes/data"
mkdir -p "$stage/compare/report"
cp compare/report/charts.py compare/report/default_sweep.json "$stage/compare/report/"
cp scripts/gpu-check.sh "$stage/scripts/"

cat >"$stage/shadowlab" <<'EOF'
#!/bin/sh
# shadowlab from an unpacked device bundle (scripts/device-bundle.sh): the bundled libraries first,
# the bundled scenes and chart script as its data ($SHADOWLAB_HOME).
here=$(cd "$(dirname "$0")" && pwd)
export LD_LIBRARY_PATH="$here/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
export SHADOWLAB_HOME="$here"
# The bundle carries the Vulkan loader (libvulkan.so.1) but no driver. A machine whose NVIDIA driver
# keeps its ICD file outside the loader's search path gets it added, unless the caller chose drivers.
nvidia_icd=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
if [ -z "${VK_DRIVER_FILES:-}${VK_ICD_FILENAMES:-}${VK_ADD_DRIVER_FILES:-}" ] && [ -f "$nvidia_icd" ]; then
  export VK_ADD_DRIVER_FILES="$nvidia_icd"
fi
exec "$here/bin/shadowlab" "$@"
EOF
chmod +x "$stage/shadowlab" "$stage/scripts/gpu-check.sh"

tar -cJf "$tarball" -C "$out" shadowlab
bytes=$(stat -c %s "$tarball")
unpacked=$(du -sb "$stage" | cut -f1)
mib() { awk -v b="$1" 'BEGIN { printf "%.1f MiB", b / 1048576 }'; }
echo "device-bundle: $tarball: $(mib "$bytes") ($bytes bytes); unpacked $(mib "$unpacked"), $(ls "$stage/lib" | wc -l) libraries"
if [ "$bytes" -gt "$limit_bytes" ]; then
  rm -f "$tarball"
  echo "device-bundle: error: the tarball is $(mib "$bytes"), over the 48 MiB limit (the device tool carries 64 MiB in all, the repository included); removed it. Look at the largest files in $stage/lib" >&2
  exit 1
fi

[ "$check" -eq 1 ] || exit 0
# ---- --check: the tarball, unpacked elsewhere, run through its launcher ---------------------------
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
tar -xJf "$tarball" -C "$tmp"
b=$tmp/shadowlab
bad=0
while read -r name arrow path _; do
  if [ "$arrow" != "=>" ]; then continue; fi
  case "$path" in
    "$b"/lib/*) ;;
    *) is_glibc "$name" || { echo "device-bundle: check: $name resolves to $path, outside the bundle" >&2; bad=1; } ;;
  esac
done < <(LD_LIBRARY_PATH="$b/lib" ldd "$b/bin/shadowlab" "$b"/lib/*.so* | grep '=>')
[ "$bad" -eq 0 ] || exit 1
echo "device-bundle: check: every library of bin/shadowlab and lib/ resolves to the bundle or to glibc"
# No shared folder and another working folder: the bundle must not lean on this checkout.
(cd "$tmp" && SHADOWLAB_SHARED_DIR="$tmp/no_shared" ./shadowlab/shadowlab scenes)
(cd "$tmp" && ./shadowlab/shadowlab devices)
(cd "$tmp" && SHADOWLAB_SHARED_DIR="$tmp/no_shared" ./shadowlab/shadowlab run grazing --device llvmpipe -o "$tmp/run")
python3 - "$tmp/run/metrics.json" <<'EOF'
import json, sys
m = json.load(open(sys.argv[1]))
print("device-bundle: check: run grazing on lavapipe through the launcher: error_rate %.6f, shadow_gpu_ms %.3f, camera_gpu_ms %.3f"
      % (m["metrics"]["error_rate"], m["timings"]["shadow_gpu_ms"], m["timings"]["camera_gpu_ms"]))
EOF
