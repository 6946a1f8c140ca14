#!/usr/bin/env bash
# The long power-loss and I/O fault run (issue 31; docs/testing.md, "Power
# loss and I/O faults"): POINTS seeded crash points with --fsync-commits and
# POINTS without (default 500 + 500 = 1,000, seeds FIRST_SEED..), split over
# SHARDS test processes run side by side (default 4: a point mostly waits on
# its processes), then, when STRIDE is set, the fault loops at every offset
# 1..STRIDE (EIO and ENOSPC on the job store and on the blob store). Too long
# for CI; CI runs a few points of the same test (cluster_power_loss_test).
#   bash bench/cluster/power_loss.sh [BUILD_DIR]    # env: POINTS, FIRST_SEED, SHARDS, STRIDE
# Prints one line per point and the totals; every failure names its seed
# (rerun one: FABATLAS_POWER_SEED=S build/bin/cluster_power_loss_test).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
build="${1:-$root/build}"
export TMPDIR="${TMPDIR:-$build/test-tmp/power}"
mkdir -p "$TMPDIR"
points="${POINTS:-500}" first="${FIRST_SEED:-1}" shards="${SHARDS:-4}"
per=$(( (points + shards - 1) / shards ))
pids=()
for ((i = 0; i < shards; i++)); do
  n=$(( points - i * per < per ? points - i * per : per ))
  (( n > 0 )) || continue
  FABATLAS_POWER_POINTS="$n" FABATLAS_POWER_FIRST_SEED=$(( first + i * per )) \
    nice -n 10 "$build/bin/cluster_power_loss_test" --gtest_filter='PowerLoss.*' > "$TMPDIR/power_loss_$i.log" 2>&1 &
  pids+=($!)
done
status=0
for p in "${pids[@]}"; do wait "$p" || status=1; done
if [ -n "${STRIDE:-}" ]; then
  FABATLAS_FAULT_STRIDE="$STRIDE" nice -n 10 "$build/bin/cluster_power_loss_test" --gtest_filter='IoFaults.*' \
    > "$TMPDIR/fault_loops.log" 2>&1 || status=1
fi
cat "$TMPDIR"/power_loss_*.log ${STRIDE:+"$TMPDIR/fault_loops.log"} | grep -E '^(power loss|fault loop|undisturbed)|FAILED|Failure' || true
# Totals over the shards: points, cuts, acknowledged results, lost ones.
for mode in with without; do
  grep -h "^power loss $mode " "$TMPDIR"/power_loss_*.log |
    awk -v m="$mode" '{p+=$5; c+=$7; a+=$9; l+=$15} END {printf "all shards, %s --fsync-commits: %d points, %d cuts, %d acknowledged, %d lost\n", m, p, c, a, l}'
done
echo "logs: $TMPDIR"
exit $status
