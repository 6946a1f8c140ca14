#!/usr/bin/env bash
# The main job on embedded defaults: installs dependencies, builds, then
# imports a spur gear (configs/scad/spur_gear.scad: MCAD's involute gear,
# Debian openscad-mcad, with Customizer sliders for its teeth, thickness and
# bore) and precomputes it on a local coordinator with two worker processes
# talking gRPC over loopback: bootstrap grid, adaptive ΔG subdivision, every
# sample's checks and properties. A bore near the gear's root circle leaves
# a rim thinner than a nozzle, so part of the space is invalid and the
# sliders stop short of it. The form, its Table-3 statistics, validity maps
# and the artifact land in out/spur_gear/. It ends with the web customiser
# for that artifact: in an
# interactive terminal `fabatlas serve` runs in the foreground (Ctrl-C stops
# it); otherwise (CI, pipes) it only prints the command, so it never blocks.
# FABATLAS_SERVE=1 / 0 forces either; FABATLAS_PORT picks the port (8080).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$root/ops/build.sh" fabatlas fabatlas-coordinator fabatlas-worker fabatlas_web
"$root/build/bin/fabatlas" run "$root/configs/scad/spur_gear.scad" --workers 2 --out "$root/out/spur_gear"
echo "validity map: $root/out/spur_gear/map_thickness_bore.png"
port="${FABATLAS_PORT:-8080}"
serve=("$root/build/bin/fabatlas" serve "$root/out/spur_gear" --port "$port")
if [ "${FABATLAS_SERVE:-$([ -t 0 ] && [ -t 1 ] && echo 1 || echo 0)}" = 1 ]; then
  echo "customiser: open http://127.0.0.1:$port/ (Ctrl-C stops the server)"
  exec "${serve[@]}"
else
  echo "customiser: run  ${serve[*]}  then open http://127.0.0.1:$port/"
fi
