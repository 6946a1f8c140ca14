#!/usr/bin/env bash
# Builds the design-parser fuzz target with clang and runs it for a bounded
# time over a seed corpus made of the example designs. Exit 0 when no crash.
# Usage: tests/fuzz/run.sh BUILD_DIR [SECONDS]
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "$here/../.." && pwd)"
build="$1"
seconds="${2:-30}"
launcher=()
command -v ccache >/dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
cmake -S "$here" -B "$build" -G Ninja -DCMAKE_CXX_COMPILER=clang++ "${launcher[@]}" >/dev/null
ninja -C "$build" design_parser_fuzz >/dev/null
corpus="$build/corpus"
mkdir -p "$corpus"
cp "$root"/configs/designs/*.yaml "$root"/tests/fuzz/regressions/* "$corpus/"
cd "$build"
./design_parser_fuzz -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 "$corpus" 2>&1 | tail -n 15
