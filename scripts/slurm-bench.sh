#!/usr/bin/env bash
# The sharding speed goal: the 100-configuration 1080p sweep of compare/SWEEPS.md ("the speed
# case") as 4 shards on a loopback Slurm (scripts/slurm-local.sh) against one `shadowlab sweep`
# process on the same machine; goal: sharded wall <= 1.3x single. Both runs write the report, both
# start from the same warm reference cache (traced once first, untimed), and they run back to back,
# alternating which goes first. The sharded wall is from `sweep --slurm 4 --submit` to the end of
# the merge job (the cluster is already up). Prints both walls and the ratio per round, then the
# median ratio, and checks that the merged metrics equal the single run's.
#
# Usage: scripts/slurm-bench.sh [--rounds R] [--shards N] [--cold] [--slurm-opt '...'] [-o DIR]
#   --rounds R   rounds of (single, sharded) pairs (default 2)
#   --shards N   shards (default 4)
#   --cold       each run starts with an empty reference cache (the shards then share its tracing)
#   --slurm-opt  passed to `sweep --slurm` (e.g. '--cpus-per-task=2')
#   -o DIR       work folder (default out/slurm-bench; results of the last round stay there)
# Environment: SHADOWLAB_BINARY (default build/app/shadowlab).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
bin=${SHADOWLAB_BINARY:-$root/build/app/shadowlab}
rounds=2
shards=4
cold=0
slurm_opts=()
work=$root/out/slurm-bench
args=("$@")
while [ $# -gt 0 ]; do
  case "$1" in
    --rounds) rounds=$2; shift 2 ;;
    --shards) shards=$2; shift 2 ;;
    --cold) cold=1; shift ;;
    --slurm-opt) slurm_opts+=("--slurm-opt=$2"); shift 2 ;;
    -o) work=$2; shift 2 ;;
    *) echo "usage: $0 [--rounds R] [--shards N] [--cold] [--slurm-opt '...'] [-o DIR]" >&2; exit 2 ;;
  esac
done
[ -x "$bin" ] || { echo "slurm-bench: error: no $bin; build first (scripts/build.sh)" >&2; exit 2; }

if [ -z "${SLURM_CONF:-}" ] || [ -z "${SHADOWLAB_SLURM_DIR:-}" ]; then
  # Not inside a cluster yet: start one around this script.
  exec "$root/scripts/slurm-local.sh" run "$0" "${args[@]}"
fi

# The speed case of compare/SWEEPS.md.
# shellcheck disable=SC2054  # the commas are the grid's values
speed=(sphere_on_plane --grid map.size=256,512,1024,2048,4096
  --grid bias.slope=0,0.5,1,1.5,2,3,4,6,8,12 --grid filter=none,pcf
  --set scene:/camera/width=1920 --set scene:/camera/height=1080)
rm -rf "$work"
mkdir -p "$work"
work=$(cd "$work" && pwd)
cd "$work"
cache=$work/cache
if [ "$cold" -eq 0 ]; then
  echo "slurm-bench: tracing the 1080p reference once (untimed)"
  "$bin" sweep sphere_on_plane --grid map.size=256 --set scene:/camera/width=1920 --set scene:/camera/height=1080 \
    --no-report --cache "$cache" -o "$work/warm" >/dev/null 2>&1
fi

# One trivial job first: slurmctld reads batch_sched_delay=0 only when it first schedules (until
# then it waits 3 s), so round 1 would pay that once.
sbatch --wait --quiet -o /dev/null --wrap true

now() { date +%s.%N; }
elapsed() { awk "BEGIN { printf \"%.2f\", $2 - $1 }"; }

single() {
  local out=$work/single t0 t1
  rm -rf "$out"
  [ "$cold" -eq 1 ] && rm -rf "$cache"
  t0=$(now)
  "$bin" sweep "${speed[@]}" --cache "$cache" -o "$out" >"$work/single.log" 2>&1 ||
    { cat "$work/single.log" >&2; exit 3; }
  t1=$(now)
  single_wall=$(elapsed "$t0" "$t1")
}

sharded() {
  local out=$work/sharded t0 t1 ids array merge
  rm -rf "$out"
  [ "$cold" -eq 1 ] && rm -rf "$cache"
  t0=$(now)
  "$bin" sweep "${speed[@]}" --cache "$cache" --slurm "$shards" "${slurm_opts[@]}" --submit -o "$out" \
    >"$work/submit.log" 2>&1 || { cat "$work/submit.log" >&2; exit 3; }
  ids=$(sed -n 's/.*as job \([0-9]*\) and the merge as job \([0-9]*\).*/\1 \2/p' "$work/submit.log")
  read -r array merge <<<"$ids"
  while [ -n "$(squeue -h -j "$array,$merge" -o %i 2>/dev/null)" ]; do sleep 0.05; done
  t1=$(now)
  scontrol -o show job "$merge" | grep -q 'JobState=COMPLETED' ||
    { echo "slurm-bench: error: the merge job failed; see $out/merge-slurm-*.out" >&2; exit 3; }
  sharded_wall=$(elapsed "$t0" "$t1")
  # Where the time went: each array task's start and end (scontrol keeps them for MinJobAge).
  scontrol -o show job "$array" | sed -n 's/.*ArrayTaskId=\([0-9]*\).* StartTime=\([^ ]*\) EndTime=\([^ ]*\).*/  task \1: \2 -> \3/p'
  scontrol -o show job "$merge" | sed -n 's/.* StartTime=\([^ ]*\) EndTime=\([^ ]*\).*/  merge: \1 -> \2/p'
}

ratios=()
echo "slurm-bench: $(nproc) CPUs, load $(cut -d' ' -f1-3 /proc/loadavg); ${shards} shards via $SLURM_CONF"
for r in $(seq 1 "$rounds"); do
  if [ $((r % 2)) -eq 1 ]; then
    single
    sharded
  else
    sharded
    single
  fi
  ratio=$(awk "BEGIN { printf \"%.3f\", $sharded_wall / $single_wall }")
  ratios+=("$ratio")
  echo "slurm-bench: round $r: single ${single_wall} s, ${shards} shards on Slurm ${sharded_wall} s, ratio ${ratio} (load $(cut -d' ' -f1 /proc/loadavg))"
done
python3 "$root/tests/support/same_metrics.py" "$work/single/results.json" "$work/sharded/results.json"
median=$(printf '%s\n' "${ratios[@]}" | sort -n | awk '{ a[NR] = $1 } END { print (NR % 2) ? a[(NR + 1) / 2] : (a[NR / 2] + a[NR / 2 + 1]) / 2 }')
verdict=$(awk "BEGIN { print ($median <= 1.3) ? \"met\" : \"missed\" }")
echo "slurm-bench: median ratio ${median} over ${rounds} round(s); goal <= 1.3: ${verdict}"
