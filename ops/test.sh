#!/usr/bin/env bash
# The whole test suite: installs dependencies, builds, runs every CTest test
# (labels: unit, integration, cluster, browser, fuzz, slow).
# Extra arguments go to ctest, e.g. `bash ops/test.sh -L unit`.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$root/ops/build.sh"
cd "$root/build"
# Tests write their scratch directories under $TMPDIR. One run's are kept in
# build/test-tmp for a look after a failure and removed when the next run
# starts, so repeated runs do not fill /tmp (a run leaves about 1 GB).
scratch="$root/build/test-tmp"
if [ -d "$scratch" ]; then
  # A disk-full test killed mid-run can leave its small tmpfs mounted.
  awk -v d="$scratch/" 'index($2, d) == 1 {print $2}' /proc/mounts | xargs -r -n1 umount -l
  rm -rf "$scratch"
fi
mkdir -p "$scratch"
export TMPDIR="$scratch"
ctest --output-on-failure --timeout 1800 -j2 "$@"
