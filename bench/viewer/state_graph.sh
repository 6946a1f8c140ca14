#!/usr/bin/env bash
# What playing a transition costs: GET /api/state_graph (the design
# evaluated at exactly u with every check, meshes and poses as JSON) on a
# real `fabatlas serve`, N times, against its peer measured in the same run:
# `fabatlas eval DESIGN --at ... --json` of the same point (the same
# evaluation and checks, without serving). Prints medians of the wall times,
# the answer's bytes and the load average.
#
#   bench/viewer/state_graph.sh RUN_DIR DESIGN U AT [N]
#   e.g. build/bin/fabatlas sample tests/viewer/data/bench_table.yaml --out /tmp/bench-run
#        bench/viewer/state_graph.sh /tmp/bench-run configs/designs/bench_table.yaml 600,150 \
#          armrest_height=600,hinge_offset=150 7
set -euo pipefail
run=$1 design=$2 u=$3 at=$4 n=${5:-7}
bin=${FABATLAS_BIN_DIR:-build/bin}
log=$(mktemp)
"$bin/fabatlas" serve "$run" --port 0 --preview-cache-mb 0 >"$log" 2>&1 &
pid=$!
trap 'kill $pid 2>/dev/null; rm -f "$log"' EXIT
for _ in $(seq 1 300); do grep -q "http://" "$log" && break; sleep 0.1; done
url=$(grep -o "http://127.0.0.1:[0-9]*/" "$log")
median() { sort -g | awk '{a[NR]=$1} END {print a[int((NR+1)/2)]}'; }
api=() eval_s=() bytes=0
for _ in $(seq 1 "$n"); do
  out=$(curl -s -o /dev/null -w "%{time_total} %{size_download}" "${url}api/state_graph?u=$u")
  api+=("${out% *}"); bytes=${out#* }
  start=$(date +%s.%N)
  "$bin/fabatlas" eval "$design" --at "$at" --json >/dev/null
  eval_s+=("$(echo "$(date +%s.%N) - $start" | bc)")
done
echo "state_graph median $(printf '%s\n' "${api[@]}" | median) s, ${bytes} bytes;" \
     "fabatlas eval median $(printf '%s\n' "${eval_s[@]}" | median) s (peer, same run); n=$n;" \
     "load $(cut -d' ' -f1-3 /proc/loadavg)"
