#!/usr/bin/env bash
# Installs what fabatlas needs and builds it (Release, Ninja, ccache when
# installed) into build/. Binaries land in build/bin/. With target names as
# arguments only those are built (ops/demo.sh builds the programs and the
# page it runs) and only the demo's packages are installed, with the tests
# and benchmarks left out of the configuration; without, everything
# (ops/test.sh: every package, the tests and benchmarks too). Every target
# builds with -Wall -Wextra; with CI=true warnings are errors.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
if (($#)); then
  bash "$root/ops/install-deps.sh" demo
  suite=OFF
else
  bash "$root/ops/install-deps.sh"
  suite=ON
fi
# CI (CI=true, as CI services set it): a warning fails the build.
werror=OFF
if [ "${CI:-}" = true ]; then werror=ON; fi
cmake -S "$root" -B "$root/build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DFABATLAS_WERROR="$werror" \
  -DFABATLAS_BUILD_TESTS="$suite" -DFABATLAS_BUILD_BENCH="$suite" >/dev/null
ninja -C "$root/build" -j"$(nproc)" "$@"
