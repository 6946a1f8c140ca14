#!/usr/bin/env bash
# The main job on embedded defaults: installs dependencies, builds, then
# precomputes the chess pawn of seed 001 (configs/jobs/pawn.yaml) on a local
# coordinator with two worker processes talking gRPC over loopback: bootstrap
# grid, adaptive ΔG subdivision, every sample's checks and properties. The
# form, its Table-3 statistics and a validity map land in out/pawn/.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$root/ops/build.sh"
"$root/build/bin/fabatlas" run "$root/configs/jobs/pawn.yaml" --workers 2 --out "$root/out/pawn"
echo "validity map: $root/out/pawn/map_head_height.png"
