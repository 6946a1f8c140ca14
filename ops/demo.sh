#!/usr/bin/env bash
# The main job on embedded defaults: installs dependencies, builds, then
# precomputes the chess pawn of seed 001 (configs/jobs/pawn.yaml): bootstrap
# grid, adaptive ΔG subdivision, every sample's checks and properties. The
# form, its Table-3 statistics and a validity map land in out/pawn/.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$root/ops/build.sh"
"$root/build/bin/fabatlas" sample "$root/configs/jobs/pawn.yaml" --out "$root/out/pawn"
echo "validity map: $root/out/pawn/map_head_height.png"
