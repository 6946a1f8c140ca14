#!/usr/bin/env bash
# The long power-loss and I/O fault run (issue 31; docs/testing.md, "Power
# loss and I/O faults"): POINTS seeded crash points with --fsync-commits and
# POINTS without (default 500 + 500 = 1,000, seeds FIRST_SEED..), split over
# SHARDS test processes run side by side (default 4, half per durability
# mode: a point mostly waits on its processes; MODES=With or MODES=Without
# runs one mode on every shard; MINUTES=m starts no point after m minutes),
# then, when STRIDE is set, the fault loops at every offset 1..STRIDE of the
# job store's writes and, when BLOB_STRIDE is set, at every offset
# 1..BLOB_STRIDE of the blob store's (EIO and ENOSPC each). Too long for CI;
# CI runs a few points of the same test (cluster_power_loss_test).
#   bash bench/cluster/power_loss.sh [BUILD_DIR]
#   env: POINTS, FIRST_SEED, SHARDS, MODES, MINUTES, STRIDE, BLOB_STRIDE
# Prints one line per point and the totals; every failure names its seed
# (rerun one: FABATLAS_POWER_SEED=S build/bin/cluster_power_loss_test).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
build="${1:-$root/build}"
export TMPDIR="${TMPDIR:-$build/test-tmp/power}"
mkdir -p "$TMPDIR"
points="${POINTS:-500}" first="${FIRST_SEED:-1}" shards="${SHARDS:-4}"
# Half the shards run points with --fsync-commits, half without, side by
# side, so a run stopped early has figures for both.
modes="${MODES:-With Without}"
nmodes=$(wc -w <<<"$modes")
per_mode=$(( shards / nmodes > 0 ? shards / nmodes : 1 ))
per=$(( (points + per_mode - 1) / per_mode ))
pids=()
for mode in $modes; do
  for ((i = 0; i < per_mode; i++)); do
    n=$(( points - i * per < per ? points - i * per : per ))
    (( n > 0 )) || continue
    FABATLAS_POWER_POINTS="$n" FABATLAS_POWER_FIRST_SEED=$(( first + i * per )) FABATLAS_POWER_MINUTES="${MINUTES:-0}" \
      nice -n 10 "$build/bin/cluster_power_loss_test" --gtest_filter="PowerLoss.${mode}FsyncCommits*" \
      > "$TMPDIR/power_loss_${mode}_$i.log" 2>&1 &
    pids+=($!)
  done
done
status=0
for p in "${pids[@]}"; do wait "$p" || status=1; done
if [ -n "${STRIDE:-}" ]; then
  FABATLAS_FAULT_STRIDE="$STRIDE" nice -n 10 "$build/bin/cluster_power_loss_test" --gtest_filter='IoFaults.*JobStore*' \
    > "$TMPDIR/fault_loops_store.log" 2>&1 || status=1
fi
if [ -n "${BLOB_STRIDE:-}" ]; then
  FABATLAS_BLOB_FAULT_STRIDE="$BLOB_STRIDE" nice -n 10 "$build/bin/cluster_power_loss_test" --gtest_filter='IoFaults.*BlobStore*' \
    > "$TMPDIR/fault_loops_blobs.log" 2>&1 || status=1
fi
cat /dev/null "$TMPDIR"/power_loss_*.log "$TMPDIR"/fault_loops_*.log 2>/dev/null |
  grep -E '^(power loss|fault loop|undisturbed)|FAILED|Failure' || true
for store in store blobs; do
  [ -f "$TMPDIR/fault_loops_$store.log" ] || continue
  grep -h '^fault loop' "$TMPDIR/fault_loops_$store.log" | awk -v s="$store" '
    {n++; match($0, /: [0-9]+ faults/); f += substr($0, RSTART + 2, RLENGTH - 9); if ($0 ~ /FAILED/) x++}
    END {printf "fault loops on the %s: %d loops, %d faults injected, %d loops failed\n", s, n, f, x}'
done
# Totals over the points (also of a run stopped early): points, cuts,
# results acknowledged before the cut, those lost, failed points.
for mode in fsync nofsync; do
  grep -h "^power point seed [0-9]* $mode:" /dev/null "$TMPDIR"/power_loss_*.log 2>/dev/null | awk -v m="$mode" '
    {n++; if ($6 == "cut,") c++
     match($0, /acknowledged [0-9]+/); a += substr($0, RSTART + 13, RLENGTH - 13)
     match($0, /lost [0-9]+/); x = substr($0, RSTART + 5, RLENGTH - 5); l += x; if (x > 0) pl++
     if ($0 ~ /FAILED/) f++}
    END {printf "%s: %d points, %d cuts, %d results acknowledged before the cut, %d of them lost (at %d points), %d points failed\n", m, n, c, a, l, pl, f}'
done
echo "logs: $TMPDIR"
exit $status
