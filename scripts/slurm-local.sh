#!/usr/bin/env bash
# A throwaway one-node Slurm cluster on this machine (loopback), to try `shadowlab sweep --slurm N
# --submit` end to end without a real cluster. Debian 12: slurm-wlm + munge; no systemd needed (the
# daemons are started by hand, so it also works in a container). Needs root (it writes /etc/slurm
# and /etc/munge); it refuses to touch a slurm.conf it did not write.
#
#   scripts/slurm-local.sh up      install (only what is missing), configure, start; waits for the node
#   scripts/slurm-local.sh demo    a small sharded sweep through sbatch (2 shards + merge) into out/slurm-demo
#   scripts/slurm-local.sh down    stop the daemons it started (the config and packages stay)
# Tried on Debian 12 (2 CPUs, in a container): up in ~2 s, the demo's 2 array tasks + merge in ~7 s,
# its results equal an unsharded sweep's in every metric.
set -euo pipefail

conf=/etc/slurm/slurm.conf
marker="# written by shadowlab scripts/slurm-local.sh"
run_dir=/run/shadowlab-slurm
host=$(hostname -s)

need_root() { [ "$(id -u)" -eq 0 ] || { echo "slurm-local: error: run as root (it writes /etc/slurm, /etc/munge)" >&2; exit 2; }; }

install() {
  local missing=()
  for p in slurm-wlm munge; do
    dpkg-query -W -f='${Status}\n' "$p" 2>/dev/null | grep -q '^install ok installed' || missing+=("$p")
  done
  [ ${#missing[@]} -eq 0 ] && return
  echo "slurm-local: installing ${missing[*]}"
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}"
}

configure() {
  if [ -e "$conf" ] && ! grep -qF "$marker" "$conf"; then
    echo "slurm-local: error: $conf exists and was not written by this script; expected none (a real cluster's config is left alone)" >&2
    exit 2
  fi
  mkdir -p /etc/slurm /var/spool/slurmctld /var/spool/slurmd /var/log/slurm "$run_dir"
  chown slurm:slurm /var/spool/slurmctld /var/log/slurm 2>/dev/null || true
  local cpus mem
  cpus=$(nproc)
  mem=$(awk '/MemTotal/ {print int($2 / 1024 * 0.8)}' /proc/meminfo)
  # proctrack/linuxproc and task/none: no cgroups needed (containers); accounting off.
  cat >"$conf" <<EOF
$marker
ClusterName=shadowlab-local
SlurmctldHost=$host
SlurmUser=root
AuthType=auth/munge
StateSaveLocation=/var/spool/slurmctld
SlurmdSpoolDir=/var/spool/slurmd
SlurmctldPidFile=$run_dir/slurmctld.pid
SlurmdPidFile=$run_dir/slurmd.pid
SlurmctldLogFile=/var/log/slurm/slurmctld.log
SlurmdLogFile=/var/log/slurm/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
MpiDefault=none
NodeName=$host CPUs=$cpus RealMemory=$mem State=UNKNOWN
PartitionName=debug Nodes=$host Default=YES MaxTime=INFINITE State=UP OverSubscribe=YES
EOF
  if [ ! -s /etc/munge/munge.key ]; then
    mkdir -p /etc/munge
    dd if=/dev/urandom bs=1 count=1024 of=/etc/munge/munge.key status=none
    chown munge:munge /etc/munge/munge.key 2>/dev/null || true
    chmod 400 /etc/munge/munge.key
  fi
}

start() {
  mkdir -p /run/munge && chown munge:munge /run/munge 2>/dev/null || true
  if ! pgrep -u munge -x munged >/dev/null; then
    if id munge >/dev/null 2>&1; then su -s /bin/sh munge -c "munged" ; else munged --force; fi
    touch "$run_dir/munged.started"  # so `down` stops only a munged this script started
  fi
  for _ in $(seq 1 20); do [ -S /run/munge/munge.socket.2 ] && break; sleep 0.5; done
  [ -s "$run_dir/slurmctld.pid" ] && kill -0 "$(cat "$run_dir/slurmctld.pid")" 2>/dev/null || slurmctld
  [ -s "$run_dir/slurmd.pid" ] && kill -0 "$(cat "$run_dir/slurmd.pid")" 2>/dev/null || slurmd
  for _ in $(seq 1 30); do
    if sinfo -h -N -o '%T' 2>/dev/null | grep -Eq '^(idle|mixed|allocated)'; then
      echo "slurm-local: up: $(sinfo -h -N -o '%N %T %c CPUs')"
      return
    fi
    sleep 1
  done
  echo "slurm-local: error: the node did not come up; see /var/log/slurm/slurmctld.log and slurmd.log" >&2
  sinfo -N >&2 || true
  exit 3
}

# SIGTERM, then wait (up to 15 s) until the process is gone, so an `up` right after starts afresh;
# a daemon still there then (seen: a slurmd that started while munged was down) gets SIGKILL.
stop_pid() {
  kill "$1" 2>/dev/null || return 0
  for _ in $(seq 1 30); do
    kill -0 "$1" 2>/dev/null || return 0
    sleep 0.5
  done
  echo "slurm-local: warning: pid $1 still running after 15 s; killing it" >&2
  kill -9 "$1" 2>/dev/null || true
}

stop() {
  for d in slurmd slurmctld; do
    [ -s "$run_dir/$d.pid" ] && stop_pid "$(cat "$run_dir/$d.pid")"
    rm -f "$run_dir/$d.pid"
  done
  if [ -e "$run_dir/munged.started" ] && [ -s /run/munge/munged.pid ]; then
    stop_pid "$(cat /run/munge/munged.pid)"
    rm -f "$run_dir/munged.started"
  fi
  echo "slurm-local: stopped the daemons it started"
}

demo() {
  local root bin out
  root=$(cd "$(dirname "$0")/.." && pwd)
  bin=${SHADOWLAB_BINARY:-$root/build/app/shadowlab}
  out=$root/out/slurm-demo
  rm -rf "$out"
  "$bin" sweep sphere_on_plane contact --grid map.size=128,512 --grid bias.slope=0,2 \
    --set scene:/camera/width=64 --set scene:/camera/height=48 --no-report --slurm 2 --submit -o "$out"
  echo "slurm-local: waiting for the jobs (squeue)"
  for _ in $(seq 1 300); do
    [ -z "$(squeue -h -u "$(id -un)" -n shadowlab-sweep,shadowlab-merge 2>/dev/null)" ] && break
    sleep 1
  done
  if [ -s "$out/results.json" ]; then
    echo "slurm-local: demo done: $out/results.json"
  else
    echo "slurm-local: error: no $out/results.json; see $out/shards/slurm-*.out and $out/merge-slurm-*.out" >&2
    exit 1
  fi
}

case "${1:-}" in
  up) need_root; install; configure; start ;;
  down) need_root; stop ;;
  demo) demo ;;
  *) echo "usage: $0 up|demo|down" >&2; exit 2 ;;
esac
