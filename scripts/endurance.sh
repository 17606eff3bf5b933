#!/usr/bin/env bash
# Endurance run (docs/benchmarks.md "Endurance"): runs a launch spec for SECONDS and samples every process of
# the launch (containers, isolated components, processes) every INTERVAL s from /proc: RSS, CPU time (utime +
# stime), threads, open files. Writes OUT/samples.csv and OUT/launch.log, then prints the per-container table
# (scripts/endurance_summary.py). Uses the cairn of ./build (run ./scripts/build.sh first) unless CAIRN_BIN_DIR
# names another bin directory.
# Usage: ./scripts/endurance.sh SECONDS [OUT] [INTERVAL] [SPEC]   (defaults: build/endurance, 20 s, demo.yaml)
set -euo pipefail
cd "$(dirname "$0")/.."
usage() { echo "usage: $0 SECONDS [OUT] [INTERVAL] [SPEC]" >&2; exit 2; }
[[ $# -ge 1 && $1 =~ ^[0-9]+$ && $1 -gt 0 ]] || usage
seconds=$1
out=${2:-build/endurance}
interval=${3:-20}
spec=${4:-launch_specs/demo.yaml}
[[ $interval =~ ^[0-9]+$ && $interval -gt 0 ]] || { echo "$0: INTERVAL must be a positive integer, got '$interval'" >&2; exit 2; }
[[ -f $spec ]] || { echo "$0: $spec: no such launch spec" >&2; exit 2; }
bin=${CAIRN_BIN_DIR:-$PWD/build/bin}
[[ -x $bin/cairn ]] || { echo "$0: $bin/cairn not found (run ./scripts/build.sh, or set CAIRN_BIN_DIR)" >&2; exit 2; }
mkdir -p "$out"
source ./scripts/env.sh
export PATH="$bin:$PATH"
git rev-parse --short HEAD > "$out/commit" 2>/dev/null || true

descendants() {
  local c
  for c in $(cat /proc/"$1"/task/*/children 2>/dev/null); do echo "$c"; descendants "$c"; done
}

cairn launch "$spec" --duration "$seconds" > "$out/launch.log" 2>&1 &
launch=$!
echo "t,pid,name,rss_kb,cpu_ticks,threads,fds" > "$out/samples.csv"
t0=$(date +%s)
while kill -0 "$launch" 2>/dev/null; do
  now=$(( $(date +%s) - t0 ))
  for p in $launch $(descendants "$launch"); do
    [[ -r /proc/$p/status ]] || continue
    name=$(tr '\0' ' ' < /proc/"$p"/cmdline | cut -c1-80 | tr -d '",')
    rss=$(awk '/^VmRSS/{print $2}' /proc/"$p"/status 2>/dev/null || true)
    threads=$(awk '/^Threads/{print $2}' /proc/"$p"/status 2>/dev/null || true)
    cpu=$(awk '{print $14 + $15}' /proc/"$p"/stat 2>/dev/null || true)
    fds=$(ls /proc/"$p"/fd 2>/dev/null | wc -l)
    [[ -n $rss && -n $cpu ]] && echo "$now,$p,\"$name\",$rss,$cpu,$threads,$fds" >> "$out/samples.csv"
  done
  sleep "$interval"
done
rc=0
wait "$launch" || rc=$?
echo "launch exited with $rc; $out/samples.csv, $out/launch.log"
python3 scripts/endurance_summary.py "$out/samples.csv" 300
exit "$rc"
