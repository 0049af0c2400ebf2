#!/usr/bin/env bash
# The same small sweep on a GPU and on lavapipe, side by side: does the GPU classify the same
# errors, and what do its timings look like? Meant for the GPU machine, run from an unpacked
# bundle (scripts/device-bundle.sh: shadowlab/scripts/gpu-check.sh), or from a checkout with
# build/app/shadowlab. Each device sweeps into its own folder (a sweep folder holds one device's
# timings, compare/SWEEPS.md); the comparison never puts two devices on one time axis: every timing
# column names its device.
#
# Usage: scripts/gpu-check.sh [--gpu NAME] [--cpu NAME] [-o DIR]
#   --gpu NAME  substring of the GPU's Vulkan device name (default NVIDIA; `shadowlab devices` lists them)
#   --cpu NAME  the reference device (default llvmpipe); skipped with a note when absent
#   -o DIR      output folder (default out/gpu-check): devices.json, <label>/results.json,
#               comparison.json and comparison.md
# Environment: SHADOWLAB (the binary or launcher to run), GPU_CHECK_GRID (extra --grid arguments,
# replacing the default axes). Exit 0 when at least one device ran, 2 on bad arguments or when no
# device matched, 3 when a sweep failed.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
gpu=NVIDIA
cpu=llvmpipe
out=out/gpu-check
while [ $# -gt 0 ]; do
  case "$1" in
    --gpu) gpu=${2:?--gpu needs a device name}; shift 2 ;;
    --cpu) cpu=${2:?--cpu needs a device name}; shift 2 ;;
    -o) out=${2:?-o needs a folder}; shift 2 ;;
    -h|--help) sed -n '2,18p' "$0"; exit 0 ;;
    *) echo "gpu-check: error: unknown argument \"$1\"; expected --gpu NAME, --cpu NAME or -o DIR" >&2; exit 2 ;;
  esac
done
if [ -z "${SHADOWLAB:-}" ]; then
  if [ -x "$here/../shadowlab" ] && [ -d "$here/../lib" ]; then SHADOWLAB=$here/../shadowlab    # unpacked bundle
  elif [ -x "$here/../build/app/shadowlab" ]; then SHADOWLAB=$here/../build/app/shadowlab     # checkout
  else echo "gpu-check: error: no shadowlab next to $here; expected an unpacked bundle or a built checkout (or SHADOWLAB=...)" >&2; exit 2
  fi
fi
mkdir -p "$out"

# The fixed set: one scene per failure family (grazing: acne; contact: leaks; sphere_on_plane: the
# analytic one; bunny: a scanned mesh) x filter x map size.
scenes=(grazing contact sphere_on_plane bunny)
grid=(--grid filter=none,hw2x2,pcf --grid map.size=1024,2048)
if [ -n "${GPU_CHECK_GRID:-}" ]; then read -r -a grid <<<"$GPU_CHECK_GRID"; fi

echo "gpu-check: Vulkan devices ($SHADOWLAB devices):"
"$SHADOWLAB" devices
"$SHADOWLAB" devices --json >"$out/devices.json"

# label:substring pairs of the devices present; the first device whose name holds the substring.
runs=()
for pair in "gpu:$gpu" "cpu:$cpu"; do
  label=${pair%%:*} want=${pair#*:}
  if python3 -c 'import json,sys; sys.exit(0 if any(sys.argv[2] in d["name"] for d in json.load(open(sys.argv[1]))) else 1)' \
       "$out/devices.json" "$want"; then
    runs+=("$label:$want")
  else
    echo "gpu-check: note: no Vulkan device matches \"$want\" ($label); it is left out of the comparison" >&2
  fi
done
if [ ${#runs[@]} -eq 0 ]; then
  echo "gpu-check: error: neither \"$gpu\" nor \"$cpu\" matches a Vulkan device (see $out/devices.json)" >&2
  exit 2
fi

for pair in "${runs[@]}"; do
  label=${pair%%:*} want=${pair#*:}
  echo "gpu-check: sweeping on \"$want\" into $out/$label"
  "$SHADOWLAB" sweep "${scenes[@]}" "${grid[@]}" --device "$want" --no-report -o "$out/$label" \
      --cache "$out/.shadowlab-cache" || { echo "gpu-check: error: the sweep on \"$want\" failed" >&2; exit 3; }
done

python3 - "$out" "${runs[@]}" <<'EOF'
# comparison.json / comparison.md: per scene and configuration, the error rates on each device
# and each device's own timings (never summed or plotted across devices).
import json, os, sys
out, runs = sys.argv[1], [r.split(":", 1)[0] for r in sys.argv[2:]]
metrics = ["error_rate", "acne_rate", "leak_rate", "aliasing_rate", "coverage_rate"]
timings = ["shadow_gpu_ms", "camera_gpu_ms"]
devices, table = {}, {}
for label in runs:
    res = json.load(open(os.path.join(out, label, "results.json")))
    names = {row.get("device", "") for row in res["rows"]}
    if len(names) != 1:
        sys.exit("gpu-check: error: %s/results.json mixes devices %s" % (label, sorted(names)))
    devices[label] = names.pop()
    for row in res["rows"]:
        key = (row["scene"], row["config"])
        entry = table.setdefault(key, {"scene": row["scene"], "config": row["config"]})
        entry[label] = {"metrics": {m: row["metrics"].get(m) for m in metrics},
                        "timings": {t: row["timings"].get(t) for t in timings}}
rows = [table[k] for k in sorted(table)]
for r in rows:
    if all(l in r for l in ("gpu", "cpu")):
        r["error_rate_difference"] = r["gpu"]["metrics"]["error_rate"] - r["cpu"]["metrics"]["error_rate"]
doc = {"schema": "shadowlab.gpu_check/1", "devices": devices, "rows": rows,
       "note": "timings are per device: each comes from its own device's clock and is never compared on one axis"}
json.dump(doc, open(os.path.join(out, "comparison.json"), "w"), indent=2)

def fmt(v, spec):
    return "-" if v is None else format(v, spec)
lines = ["# gpu-check", ""]
for label in runs:
    lines.append("* %s: `%s`" % (label, devices[label]))
lines += ["", "Error rates (share of compared pixels) per device; timings in ms, each on its own device.", ""]
head = ["scene", "config"]
for label in runs:
    head += ["%s %s" % (label, m) for m in metrics]
for label in runs:
    head += ["%s %s [%s]" % (label, t, devices[label]) for t in timings]
lines.append("| " + " | ".join(head) + " |")
lines.append("|" + "---|" * len(head))
for r in rows:
    cells = [r["scene"], r["config"]]
    for label in runs:
        cells += [fmt(r.get(label, {}).get("metrics", {}).get(m), ".5f") for m in metrics]
    for label in runs:
        cells += [fmt(r.get(label, {}).get("timings", {}).get(t), ".3f") for t in timings]
    lines.append("| " + " | ".join(cells) + " |")
open(os.path.join(out, "comparison.md"), "w").write("\n".join(lines) + "\n")
print("gpu-check: wrote %s and %s (%d rows, devices: %s)" % (os.path.join(out, "comparison.md"),
      os.path.join(out, "comparison.json"), len(rows), "; ".join("%s = %s" % kv for kv in devices.items())))
EOF
