#!/usr/bin/env bash
# The long power-loss and I/O fault run (issue 31; docs/testing.md, "Power
# loss and I/O faults"): POINTS seeded crash points with --fsync-commits and
# POINTS without (default 500 + 500 = 1,000), then, when STRIDE is set, the
# fault loops at every offset 1..STRIDE (EIO and ENOSPC on the job store and
# on the blob store). Too long for CI (about 8 s a point on 2 cores); CI runs
# a few points of the same test (cluster_power_loss_test).
#   bash bench/cluster/power_loss.sh [BUILD_DIR]     # env: POINTS, FIRST_SEED, STRIDE
# Prints one line per point and the totals; every failure names its seed
# (rerun one: FABATLAS_POWER_SEED=S build/bin/cluster_power_loss_test).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
build="${1:-$root/build}"
export TMPDIR="${TMPDIR:-$build/test-tmp/power}"
mkdir -p "$TMPDIR"
log="$TMPDIR/power_loss.log"
: > "$log"
export FABATLAS_POWER_POINTS="${POINTS:-500}" FABATLAS_POWER_FIRST_SEED="${FIRST_SEED:-1}"
status=0
nice -n 10 "$build/bin/cluster_power_loss_test" --gtest_filter='PowerLoss.*' >> "$log" 2>&1 || status=1
if [ -n "${STRIDE:-}" ]; then
  FABATLAS_FAULT_STRIDE="$STRIDE" nice -n 10 "$build/bin/cluster_power_loss_test" --gtest_filter='IoFaults.*' \
    >> "$log" 2>&1 || status=1
fi
grep -E '^(power loss|fault loop)|FAILED|Failure' "$log" || true
echo "full log: $log"
exit $status
