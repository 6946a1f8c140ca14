#!/usr/bin/env bash
# Installs what fabatlas needs on Debian bookworm. `install-deps.sh demo`:
# only what ops/demo.sh builds and runs (the compilers and libraries of the
# programs, OpenSCAD and MCAD for the spur gear, Node.js for the customiser
# page); without an argument, that and everything the test suite and the
# benchmarks need too (ops/test.sh, .ci/run).
# Idempotent: packages already present are not fetched again, and the package
# index is refreshed at most once per call (only when something is missing).
set -euo pipefail

set_name="${1:-all}"
case "$set_name" in
  demo | all) ;;
  *)
    echo "install-deps: unknown package set '$set_name' (demo or all)" >&2
    exit 2
    ;;
esac

# What the demo builds (every library CMake configures) and runs.
DEMO_PACKAGES=(
  build-essential cmake ninja-build pkg-config
  libopenvdb-dev libboost-iostreams-dev libtbb-dev libblosc-dev
  libcgal-dev libgmp-dev libmpfr-dev libpolyclipping-dev
  libopenmesh-dev libembree-dev
  libceres-dev libeigen3-dev libsuitesparse-dev
  libgrpc++-dev protobuf-compiler-grpc libprotobuf-dev protobuf-compiler
  libsqlite3-dev
  libyaml-cpp-dev libmuparser-dev nlohmann-json3-dev libcli11-dev libspdlog-dev
  libcpp-httplib-dev libtinygltf-dev libstb-dev libpng-dev libzstd-dev libssl-dev libexpat1-dev
  libglpk-dev libfcl-dev
  # the spur gear: OpenSCAD exports its geometry, MCAD holds its involute gear
  openscad openscad-mcad
  fonts-dejavu-core
)
# What only the tests and benchmarks need.
TEST_PACKAGES=(
  ccache clang libclang-rt-14-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  sqlite3
  # real OpenSCAD models nobody on the team wrote: the corpus of the mesh road's
  # coverage tests and benchmark (docs/openscad.md)
  openscad-testing-data
  chromium
  # peers and operators' tools: CalculiX (FEM side by side), Slurm + munge
  # (the slurm test), Dask (task-throughput peer)
  calculix-ccx
  munge slurmctld slurmd slurm-client
  python3-distributed
  # tests: certificates made by the TLS test, the journal syncs --fsync-commits makes
  openssl strace
  # the layout check (tests/format_check.sh, .clang-format)
  clang-format-14
  # a peer's mesh volumes: ADMesh, for the FabHacks volumes of tests/mesh (fabhacks_admesh_volumes.sh)
  admesh
  # a slicer: PrusaSlicer's CLI slices the exported 3MF and STL of OpenSCAD
  # models' parts (tests/scad/slice_parts_test.py)
  prusa-slicer
)
APT_PACKAGES=("${DEMO_PACKAGES[@]}")
if [ "$set_name" = all ]; then APT_PACKAGES+=("${TEST_PACKAGES[@]}"); fi
# Node.js and npm: the machine's own if present, else Debian's.
command -v npm >/dev/null 2>&1 || APT_PACKAGES+=(nodejs npm)

missing=()
for p in "${APT_PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if ((${#missing[@]})); then
  echo "install-deps: installing ${#missing[@]} Debian packages: ${missing[*]}"
  SUDO=""
  if [ "$(id -u)" != 0 ]; then SUDO=sudo; fi
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

# Node packages (test meshes, the web customiser's three.js, playwright-core)
# are pinned by package-lock.json at the repository root.
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
if [ -f "$root/package.json" ]; then
  if [ ! -d "$root/node_modules" ] || [ "$root/package-lock.json" -nt "$root/node_modules/.package-lock.json" ]; then
    echo "install-deps: installing npm packages"
    # npm ci refuses a lock file that lacks any platform's optional package;
    # when the registry mirror changes under us, fall back to a resolving
    # install (same pinned top-level versions) rather than fail the set-up.
    if ! (cd "$root" && npm ci --no-audit --no-fund --loglevel=error); then
      echo "install-deps: npm ci failed; resolving with npm install instead" >&2
      (cd "$root" && npm install --no-audit --no-fund --no-save --loglevel=error)
    fi
  fi
fi
