#!/usr/bin/env bash
# Installs what fabatlas needs and builds it (Release, Ninja, ccache) into
# build/. Binaries land in build/bin/. With target names as arguments only
# those are built (ops/demo.sh builds the programs and the page it runs);
# without, everything (ops/test.sh: the tests and benchmarks too).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$root/ops/install-deps.sh"
cmake -S "$root" -B "$root/build" -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
ninja -C "$root/build" -j"$(nproc)" "$@"
