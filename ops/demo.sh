#!/usr/bin/env bash
# The main job on embedded defaults: installs dependencies, builds, and
# evaluates every example design in configs/designs at its default point,
# reporting its checks and properties.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$root/ops/build.sh"
for design in "$root"/configs/designs/*.yaml; do
  "$root/build/bin/fabatlas" eval "$design"
done
