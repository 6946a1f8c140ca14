#!/usr/bin/env bash
# The enclosed volume of each FabHacks part mesh as ADMesh 0.98 computes it
# (`admesh -c`: no checks or repairs, the signed volume of the facets as
# read), the peer answer behind kFabHacks in mesh_report_test.cc for the
# meshes whose mass EXAMPLES.md does not publish. ADMesh reads STL only: OBJ
# and OFF files are rewritten here as binary STL (vertices as written, faces
# of more than three corners as fans, each facet's unit normal from its
# corners' order, which ADMesh's volume formula reads) by a few lines of Python, not by
# fabatlas's mesh reader.
# Usage: tests/mesh/fabhacks_admesh_volumes.sh [MESH_DIR]   (needs admesh, python3)
set -euo pipefail
dir="${1:-${FABATLAS_SHARED_DIR:-$(cd "$(dirname "$0")/../../.." && pwd)/shared}/data/fabhacks/meshes}"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT

for f in "$dir"/*.obj "$dir"/*.off "$dir"/*.stl; do
  name="$(basename "$f")"
  case "$f" in
    *.stl) cp "$f" "$tmp/mesh.stl" ;;
    *) python3 - "$f" "$tmp/mesh.stl" <<'PY'
import struct, sys
src, out = sys.argv[1], sys.argv[2]
v, faces = [], []
words = [line.split('#')[0].split() for line in open(src)]
words = [w for w in words if w]
if src.endswith('.obj'):
    for w in words:
        if w[0] == 'v':
            v.append(tuple(float(x) for x in w[1:4]))
        elif w[0] == 'f':
            ids = [int(x.split('/')[0]) for x in w[1:]]
            faces.append([i - 1 if i > 0 else len(v) + i for i in ids])
else:  # OFF: "OFF" then counts (on its line or the next), vertices, faces
    tokens = [t for w in words for t in w]
    assert tokens[0].startswith('OFF')
    nv, nf = int(tokens[1]), int(tokens[2])
    at = 4
    for _ in range(nv):
        v.append(tuple(float(x) for x in tokens[at:at + 3])); at += 3
    for _ in range(nf):
        k = int(tokens[at]); faces.append([int(x) for x in tokens[at + 1:at + 1 + k]]); at += 1 + k
tris = [(f[0], f[i], f[i + 1]) for f in faces for i in range(1, len(f) - 1)]
with open(out, 'wb') as o:
    o.write(b'\0' * 80 + struct.pack('<I', len(tris)))
    for t in tris:  # ADMesh's volume uses the stored unit normals
        a, b, c = v[t[0]], v[t[1]], v[t[2]]
        u = [b[i] - a[i] for i in range(3)]; w = [c[i] - a[i] for i in range(3)]
        n = [u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]]
        length = sum(x * x for x in n) ** 0.5 or 1.0
        o.write(struct.pack('<12fH', *(x / length for x in n), *a, *b, *c, 0))
PY
    ;;
  esac
  volume="$(admesh -c "$tmp/mesh.stl" | awk '/Volume/ { print $NF }')"
  printf '%s %s\n' "$name" "$volume"
done | sort
