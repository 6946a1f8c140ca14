#!/usr/bin/env bash
# The install tree (issue 16): `cmake --install` into a temporary prefix, then
# a job run from the installed binaries alone (fabatlas run starts the
# installed fabatlas-worker beside it), --version on all three, and the
# installed units pointing at the installed binaries.
#   tests/ops/install_test.sh SOURCE_DIR BUILD_DIR
set -euo pipefail
src=$(cd "${1:?source dir}" && pwd)
build=$(cd "${2:?build dir}" && pwd)
tmp=$(mktemp -d /tmp/fabatlas-install.XXXXXX)
trap 'rm -rf "$tmp"' EXIT
prefix=$tmp/prefix
cmake --install "$build" --prefix "$prefix" > "$tmp/install.log"
for f in bin/fabatlas bin/fabatlas-coordinator bin/fabatlas-worker lib/systemd/system/fabatlas-coordinator.service \
         lib/systemd/system/fabatlas-worker@.service share/fabatlas/slurm/fabatlas-workers.sbatch \
         share/fabatlas/tls/make-certs.sh share/fabatlas/k8s/fabatlas.yaml share/doc/fabatlas/operations.md; do
  [[ -e $prefix/$f ]] || { echo "not installed: $f"; exit 1; }
done
if [[ -f $build/web/index.html && ! -f $prefix/share/fabatlas/web/index.html ]]; then
  echo "the built web page was not installed"; exit 1
fi
for b in fabatlas fabatlas-coordinator fabatlas-worker; do
  v=$("$prefix/bin/$b" --version)
  [[ $v == "$b "[0-9]* ]] || { echo "$b --version: '$v'"; exit 1; }
  echo "$v"
done
grep -q "^ExecStart=$prefix/bin/fabatlas-coordinator " "$prefix/lib/systemd/system/fabatlas-coordinator.service" ||
  { echo "installed coordinator unit does not start $prefix/bin/fabatlas-coordinator"; exit 1; }
grep -q "^ExecStart=$prefix/bin/fabatlas-worker " "$prefix/lib/systemd/system/fabatlas-worker@.service" ||
  { echo "installed worker unit does not start $prefix/bin/fabatlas-worker"; exit 1; }

# A job from the installed tree only: the job file and design copied out of
# the source tree, run from their own directory with relative paths.
mkdir "$tmp/job"
cp "$src/configs/designs/tube_wall_2d.yaml" "$tmp/job/"
sed 's#^design: .*#design: tube_wall_2d.yaml#' "$src/tests/cluster/data/tube_small.yaml" > "$tmp/job/job.yaml"
(cd "$tmp/job" && env -i PATH=/usr/bin:/bin HOME="$tmp" "$prefix/bin/fabatlas" run job.yaml --workers 2 --out out --quiet)
(cd "$tmp/job" && "$build/bin/fabatlas" sample job.yaml --out reference > /dev/null)
cmp "$tmp/job/out/form.json" "$tmp/job/reference/form.json"
"$prefix/bin/fabatlas" inspect "$tmp/job/out/tube_wall_2d.fabatlas" > /dev/null
echo "installed tree ran the job: form.json identical to fabatlas sample's"
