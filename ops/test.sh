#!/usr/bin/env bash
# The whole test suite: installs dependencies, builds, runs every CTest test
# (labels: unit, integration, cluster, browser, fuzz, slow).
# Extra arguments go to ctest, e.g. `bash ops/test.sh -L unit`.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$root/ops/build.sh"
cd "$root/build"
ctest --output-on-failure --timeout 1800 -j2 "$@"
