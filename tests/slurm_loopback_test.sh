#!/usr/bin/env bash
# CTest `slurm_loopback` (label slurm): a real Slurm on loopback (scripts/slurm-local.sh, everything
# in a temporary folder) runs `shadowlab sweep ... --slurm 4 --submit`: a 4-task array of shards and
# the dependent merge job. The merged results must equal an unsharded run of the same plan in every
# metric (tests/support/same_metrics.py), and the comparison must catch a doctored metric and a
# dropped row. The cluster is torn down on every exit (trap).
# Without slurm-wlm/munge it installs them when it can (root, or passwordless sudo); when it cannot,
# it skips (exit 77, SKIP_RETURN_CODE) saying so, or fails under CI=true.
#   usage: slurm_loopback_test.sh SHADOWLAB_BINARY SOURCE_DIR
set -euo pipefail
bin=$1
src=$2
slurm_local=$src/scripts/slurm-local.sh
same_metrics=$src/tests/support/same_metrics.py

fail() {
  echo "slurm_loopback: FAIL: $*" >&2
  exit 1
}
unavailable() {
  if [ "${CI:-}" = true ]; then
    fail "$* (CI=true: this test must run there, not skip)"
  fi
  echo "slurm_loopback: SKIP: $*" >&2
  exit 77
}

if ! "$slurm_local" check 2>/dev/null; then
  "$slurm_local" install ||
    unavailable "slurm-wlm and munge are not installed and cannot be installed here ($slurm_local install failed: needs root or passwordless sudo, and apt); run scripts/install-deps.sh"
  "$slurm_local" check || fail "slurm-wlm and munge are installed, yet their programs are missing (see above)"
fi

work=$(mktemp -d /tmp/shadowlab_slurm_test.XXXXXX)
cluster=$(mktemp -d /tmp/shadowlab-slurm.XXXXXX)
cleanup() {
  local status=$?
  if [ "$status" -ne 0 ]; then
    for f in "$work"/gen/shards/slurm-*.out "$work"/gen/merge-slurm-*.out; do
      [ -e "$f" ] && { echo "----- $f" >&2; tail -n 20 "$f" >&2; }
    done
  fi
  "$slurm_local" down "$cluster" || true
  rm -rf "$work"
  exit "$status"
}
trap cleanup EXIT
trap 'exit 130' INT
trap 'exit 143' TERM

eval "$("$slurm_local" up "$cluster")"
[ "$SLURM_CONF" = "$cluster/slurm.conf" ] || fail "up exported SLURM_CONF=$SLURM_CONF; expected $cluster/slurm.conf"

# 2 scenes x 4 configurations at 64x48: 8 rows, 2 per shard. The shards start with an empty
# reference cache, so they trace (and write) the same entries side by side.
# shellcheck disable=SC2054  # the commas are the grid's values
plan=(sphere_on_plane contact --grid map.size=128,512 --grid bias.slope=0,2
  --set scene:/camera/width=64 --set scene:/camera/height=48 --no-report --cache "$work/cache")
cd "$work"
t0=$(date +%s.%N)
"$bin" sweep "${plan[@]}" --slurm 4 --submit -o "$work/gen" >"$work/submit.txt" 2>&1 || {
  cat "$work/submit.txt" >&2
  fail "shadowlab sweep --slurm 4 --submit failed"
}
cat "$work/submit.txt"
read -r array_id merge_id < <(sed -n 's/.*as job \([0-9]*\) and the merge as job \([0-9]*\).*/\1 \2/p' "$work/submit.txt")
if [ -z "${array_id:-}" ] || [ -z "${merge_id:-}" ]; then fail "no job ids in the --submit output"; fi

# Both jobs leave the queue when done (MinJobAge keeps them visible to scontrol for their state).
for _ in $(seq 1 1200); do
  [ -z "$(squeue -h -j "$array_id,$merge_id" -o %i 2>/dev/null)" ] && break
  sleep 0.1
done
[ -z "$(squeue -h -j "$array_id,$merge_id" -o %i 2>/dev/null)" ] || {
  squeue >&2
  fail "the jobs did not finish in 120 s"
}
t1=$(date +%s.%N)
states=$(scontrol -o show job "$array_id" | grep -o 'JobState=[A-Z_]*' | sort | uniq -c | tr -s ' ')
echo "slurm_loopback: array job $array_id: $states"
tasks=$(scontrol -o show job "$array_id" | grep -c 'JobState=COMPLETED' || true)
[ "$tasks" -eq 4 ] || fail "expected 4 COMPLETED array tasks, got: $states"
scontrol -o show job "$merge_id" | grep -q 'JobState=COMPLETED' ||
  fail "the merge job $merge_id did not complete: $(scontrol -o show job "$merge_id" | grep -o 'JobState=[A-Z_]*')"
for i in 0 1 2 3; do
  [ -s "$work/gen/shards/$i-of-4/rows.jsonl" ] || fail "shard $i wrote no rows"
done
[ -s "$work/gen/results.json" ] || fail "the merge wrote no results.json"
echo "slurm_loopback: 4 shards + merge through sbatch in $(awk "BEGIN { printf \"%.1f\", $t1 - $t0 }") s"

"$bin" sweep "${plan[@]}" -o "$work/one" >/dev/null 2>"$work/one.log" || {
  cat "$work/one.log" >&2
  fail "the unsharded sweep failed"
}
python3 "$same_metrics" "$work/one/results.json" "$work/gen/results.json" || fail "merged != unsharded"
rows=$(python3 -c 'import json,sys; print(len(json.load(open(sys.argv[1]))["rows"]))' "$work/gen/results.json")
[ "$rows" -eq 8 ] || fail "expected 8 merged rows, got $rows"

# The comparison can fail: one metric moved by one ulp, then one row dropped.
python3 - "$work/gen/results.json" "$work/doctored.json" "$work/dropped.json" <<'EOF'
import json, math, sys
doc = json.load(open(sys.argv[1]))
row = doc["rows"][5]
row["metrics"]["shadow_iou"] = math.nextafter(row["metrics"]["shadow_iou"], 2.0)
json.dump(doc, open(sys.argv[2], "w"))
del doc["rows"][3]
json.dump(doc, open(sys.argv[3], "w"))
EOF
if python3 "$same_metrics" "$work/one/results.json" "$work/doctored.json" 2>"$work/doctored.err"; then
  fail "a metric moved by one ulp went unnoticed"
fi
grep -q 'metric shadow_iou' "$work/doctored.err" || fail "the doctored metric was not named: $(cat "$work/doctored.err")"
if python3 "$same_metrics" "$work/one/results.json" "$work/dropped.json" 2>"$work/dropped.err"; then
  fail "a dropped row went unnoticed"
fi
grep -q 'is only in' "$work/dropped.err" || fail "the dropped row was not named: $(cat "$work/dropped.err")"
echo "slurm_loopback: PASS: merged results of 4 Slurm shards equal the unsharded run in every metric"
