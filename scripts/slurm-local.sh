#!/usr/bin/env bash
# A throwaway one-node Slurm cluster on loopback, living entirely in one temporary folder: its own
# munge key, socket and seed, its own slurm.conf (SLURM_CONF), state, spool, logs and pid files, on
# free ports. It writes nothing under /etc, needs no systemd (the daemons are started by hand, so it
# works in a container) and does not disturb a real cluster or another loopback cluster on the machine.
# Debian 12: slurm-wlm + munge (scripts/install-deps.sh installs them). Runs as any user: the daemons
# run as the user who starts them (SlurmUser, SlurmdUser), so only that user's jobs can run there.
#
#   scripts/slurm-local.sh up [DIR]    start one in DIR (default: a new /tmp/shadowlab-slurm.XXXXXX);
#                                      waits until the node is idle; prints on stdout
#                                      `export SLURM_CONF=DIR/slurm.conf SHADOWLAB_SLURM_DIR=DIR`
#                                      (so: eval "$(scripts/slurm-local.sh up)")
#   scripts/slurm-local.sh down [DIR]  cancel its jobs, stop its daemons by their saved pids, remove DIR
#                                      (default DIR: $SHADOWLAB_SLURM_DIR)
#   scripts/slurm-local.sh run CMD...  up, run CMD with SLURM_CONF set, down (also when CMD fails or on
#                                      Ctrl-C); exits with CMD's status
#   scripts/slurm-local.sh demo        `run` around a small 2-shard sweep through sbatch into out/slurm-demo
#   scripts/slurm-local.sh check       exit 0 when the packages' programs are there, else 3 naming them
#   scripts/slurm-local.sh install     apt-get install slurm-wlm munge, only what is missing (root or sudo -n)
# Exit status: 2 usage, 3 programs missing (or not installable), 4 the cluster did not come up (its logs are printed).
# Measured on Debian 12 (2 CPUs shared with other work, in a container, slurm-wlm 22.05.8, munge
# 0.5.15): up in ~1.5 s; the 4-task array + dependent merge of tests/slurm_loopback_test.sh (8 rows
# at 64x48) in 6.5 s, about 3 s of it Slurm's own latency (slurmctld schedules once a second); down ~2 s.
set -euo pipefail

marker=shadowlab-slurm-local
programs=(munged slurmctld slurmd sbatch squeue sinfo scontrol scancel)

log() { echo "slurm-local: $*" >&2; }
die() {
  local code=$1
  shift
  log "error: $*"
  exit "$code"
}

missing_programs() {
  local p out=()
  for p in "${programs[@]}"; do
    command -v "$p" >/dev/null 2>&1 || [ -x "/usr/sbin/$p" ] || out+=("$p")
  done
  echo "${out[*]}"
}

check() {
  local m
  m=$(missing_programs)
  [ -z "$m" ] || die 3 "missing $m; expected Debian's slurm-wlm and munge (scripts/install-deps.sh, or $0 install)"
}

# As root, or through passwordless sudo; exit 3 when neither is possible or apt-get fails.
install() {
  local p missing=() sudo_cmd=()
  for p in slurm-wlm munge; do
    dpkg-query -W -f='${Status}\n' "$p" 2>/dev/null | grep -q '^install ok installed' || missing+=("$p")
  done
  [ ${#missing[@]} -eq 0 ] && return 0
  if [ "$(id -u)" -ne 0 ]; then
    sudo -n true 2>/dev/null || die 3 "install: ${missing[*]} missing; installing needs root or passwordless sudo"
    sudo_cmd=(sudo -n)
  fi
  log "installing ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >&2 ||
    { "${sudo_cmd[@]}" apt-get update -qq >&2 &&
      "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >&2; } ||
    die 3 "install: apt-get install ${missing[*]} failed"
}

# Two distinct TCP ports free on loopback right now (the kernel picks them; both sockets are held
# until both are known, so they differ).
free_ports() {
  python3 - <<'EOF'
import socket
socks = []
for _ in range(2):
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    socks.append(s)
print(" ".join(str(s.getsockname()[1]) for s in socks))
EOF
}

# Starts CMD in its own session (so a Ctrl-C meant for the caller reaches the daemons only through
# `down`), in the foreground mode of the daemon, output to LOG; saves its pid in DIR/pids/NAME.
start_daemon() {
  local dir=$1 name=$2
  shift 2
  setsid "$@" </dev/null >>"$dir/log/$name.log" 2>&1 &
  echo $! >"$dir/pids/$name"
}

pid_alive() { [ -s "$1" ] && kill -0 "$(cat "$1")" 2>/dev/null; }

print_logs() {
  local f
  for f in "$1"/log/*.log; do
    [ -e "$f" ] || continue
    echo "----- $f (last 30 lines)" >&2
    tail -n 30 "$f" >&2
  done
}

up() {
  check
  local dir=${1:-}
  if [ -z "$dir" ]; then
    dir=$(mktemp -d /tmp/shadowlab-slurm.XXXXXX)
  else
    [ ! -e "$dir" ] || [ -z "$(ls -A "$dir")" ] || die 2 "up: $dir exists and is not empty; expected a new folder"
    mkdir -p "$dir"
  fi
  dir=$(cd "$dir" && pwd)
  # munged wants every folder on its socket's path searchable by all and none writable by others.
  chmod 755 "$dir"
  echo "$marker" >"$dir/.marker"
  mkdir -p "$dir/log" "$dir/pids" "$dir/state" "$dir/spool" "$dir/munge"
  chmod 700 "$dir/munge"
  local key=$dir/munge/munge.key sock=$dir/munge.socket
  PATH=$PATH:/usr/sbin
  # This cluster's own key (mungekey comes with munge >= 0.5.14; else 1 KiB of urandom, the same thing).
  mungekey --create --keyfile="$key" >/dev/null 2>&1 || dd if=/dev/urandom bs=1 count=1024 of="$key" status=none
  chmod 400 "$key"

  local ctld_port slurmd_port cpus user d
  user=$(id -un)
  read -r ctld_port slurmd_port <<<"$(free_ports)"
  cpus=$(nproc)
  : >"$dir/plugstack.conf"
  cat >"$dir/slurm.conf" <<EOF
# $marker: a throwaway loopback cluster; everything it writes is under $dir
ClusterName=shadowlab-local
SlurmctldHost=localhost
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
SlurmUser=$user
SlurmdUser=$user
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$sock
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool/%n
SlurmctldPidFile=$dir/pids/slurmctld.pidfile
SlurmdPidFile=$dir/pids/slurmd.pidfile
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
SlurmSchedLogFile=$dir/log/sched.log
PlugStackConfig=$dir/plugstack.conf
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MailProg=/bin/true
SchedulerType=sched/backfill
SchedulerParameters=batch_sched_delay=0
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
MpiDefault=none
MinJobAge=300
LogTimeFormat=iso8601_ms
NodeName=localhost NodeAddr=127.0.0.1 CPUs=$cpus State=UNKNOWN
PartitionName=local Nodes=localhost Default=YES MaxTime=INFINITE State=UP
EOF
  export SLURM_CONF=$dir/slurm.conf
  start_daemon "$dir" munged munged -F --key-file="$key" --socket="$sock" --pid-file="$dir/munge/munged.pid" \
    --log-file="$dir/log/munged.log" --seed-file="$dir/munge/munged.seed"
  for _ in $(seq 1 100); do
    [ -S "$sock" ] && break
    pid_alive "$dir/pids/munged" || { print_logs "$dir"; down "$dir"; die 4 "munged exited; its log is above"; }
    sleep 0.1
  done
  [ -S "$sock" ] || { print_logs "$dir"; down "$dir"; die 4 "munged made no socket $sock in 10 s"; }
  start_daemon "$dir" slurmctld slurmctld -D -c -f "$dir/slurm.conf"
  start_daemon "$dir" slurmd slurmd -D -N localhost -f "$dir/slurm.conf"
  for _ in $(seq 1 300); do
    if sinfo -h -N -o '%T' 2>/dev/null | grep -Eq '^(idle|mixed|allocated)'; then
      log "up in $dir: node localhost $(sinfo -h -N -o '%T, %c CPUs'), slurmctld port $ctld_port, slurmd port $slurmd_port"
      echo "export SLURM_CONF=$dir/slurm.conf SHADOWLAB_SLURM_DIR=$dir"
      return 0
    fi
    for d in munged slurmctld slurmd; do
      pid_alive "$dir/pids/$d" || { print_logs "$dir"; down "$dir"; die 4 "$d exited; its log is above"; }
    done
    sleep 0.1
  done
  print_logs "$dir"
  sinfo -N >&2 || true
  down "$dir"
  die 4 "the node did not come up in 30 s; the logs are above"
}

# SIGTERM to every pid at once (each daemon takes ~2 s to exit), then up to 10 s for them to go,
# then SIGKILL to what is left.
stop_pids() {
  local pid alive
  for pid in "$@"; do kill "$pid" 2>/dev/null || true; done
  for _ in $(seq 1 100); do
    alive=()
    for pid in "$@"; do kill -0 "$pid" 2>/dev/null && alive+=("$pid"); done
    [ ${#alive[@]} -eq 0 ] && return 0
    sleep 0.1
  done
  log "warning: pid(s) ${alive[*]} still running after 10 s; killing them"
  kill -9 "${alive[@]}" 2>/dev/null || true
}

down() {
  local dir=${1:-${SHADOWLAB_SLURM_DIR:-}}
  [ -n "$dir" ] || die 2 "down: which cluster? expected its folder (or \$SHADOWLAB_SLURM_DIR from up)"
  [ -d "$dir" ] || { log "down: $dir is gone already"; return 0; }
  [ "$(cat "$dir/.marker" 2>/dev/null)" = "$marker" ] ||
    die 2 "down: $dir was not made by $0 up (no $dir/.marker); refusing to touch it"
  export SLURM_CONF=$dir/slurm.conf
  PATH=$PATH:/usr/sbin
  # Its jobs first (only this cluster's: SLURM_CONF names it), so no job outlives the daemons.
  if pid_alive "$dir/pids/slurmctld" && [ -n "$(squeue -h -o %i 2>/dev/null)" ]; then
    scancel --full "--user=$(id -un)" 2>/dev/null || true
    for _ in $(seq 1 100); do
      [ -z "$(squeue -h -o %i 2>/dev/null)" ] && break
      sleep 0.1
    done
  fi
  local d pids=()
  for d in slurmd slurmctld munged; do
    # Only a process that is still this cluster's daemon (its command line names DIR), not a
    # stranger that reused a stale pid.
    if [ -s "$dir/pids/$d" ] && tr '\0' ' ' <"/proc/$(cat "$dir/pids/$d")/cmdline" 2>/dev/null | grep -qF "$dir/"; then
      pids+=("$(cat "$dir/pids/$d")")
    fi
  done
  [ ${#pids[@]} -eq 0 ] || stop_pids "${pids[@]}"
  rm -rf "$dir"
  log "down: stopped its daemons, removed $dir"
}

run() {
  [ $# -gt 0 ] || die 2 "run: expected a command"
  local env status=0
  env=$(up) || exit $?
  cluster_dir=${env##*SHADOWLAB_SLURM_DIR=}
  trap 'down "$cluster_dir"' EXIT
  trap 'exit 130' INT
  trap 'exit 143' TERM
  eval "$env"
  "$@" || status=$?
  return "$status"
}

demo() {
  local root bin out
  root=$(cd "$(dirname "$0")/.." && pwd)
  bin=${SHADOWLAB_BINARY:-$root/build/app/shadowlab}
  out=$root/out/slurm-demo
  rm -rf "$out"
  "$bin" sweep sphere_on_plane contact --grid map.size=128,512 --grid bias.slope=0,2 \
    --set scene:/camera/width=64 --set scene:/camera/height=48 --no-report --slurm 2 --submit -o "$out"
  log "waiting for the jobs (squeue)"
  for _ in $(seq 1 600); do
    [ -z "$(squeue -h -o %i 2>/dev/null)" ] && break
    sleep 0.2
  done
  if [ -s "$out/results.json" ]; then
    log "demo done: $out/results.json"
  else
    die 1 "no $out/results.json; see $out/shards/slurm-*.out and $out/merge-slurm-*.out"
  fi
}

cmd=${1:-}
[ $# -gt 0 ] && shift
case "$cmd" in
  up) up "$@" ;;
  down) down "$@" ;;
  run) run "$@" ;;
  demo) run "$0" demo-inside ;;
  demo-inside) demo ;;
  check) check ;;
  install) install ;;
  *)
    echo "usage: $0 up [DIR] | down [DIR] | run CMD... | demo | check | install" >&2
    exit 2
    ;;
esac
