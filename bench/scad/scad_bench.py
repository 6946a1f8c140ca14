#!/usr/bin/env python3
"""OpenSCAD models through fabatlas against OpenSCAD itself (docs/openscad.md).

  bench/scad/scad_bench.py speed [--repeats 3]   tray, sign.scad, candleStand.scad:
      OpenSCAD's own STL render wall time vs one fabatlas sample (geometry:
      .csg export + native CSG; whole sample: with the design's checks),
      medians of --repeats, volume of each STL.
  bench/scad/scad_bench.py coverage               every example Debian's openscad ships:
      evaluated natively (how many CSG subtrees native, how many OpenSCAD
      rendered) and the volume difference to OpenSCAD's own STL.

Run from the repository root with build/bin/fabatlas built. Volumes are those
the surfaces enclose (divergence theorem over the STL triangles).
"""
import json, os, re, statistics, struct, subprocess, sys, tempfile, time, glob

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
FABATLAS = os.environ.get("FABATLAS_BIN", os.path.join(ROOT, "build", "bin", "fabatlas"))
EXAMPLES = "/usr/share/openscad/examples"


def stl_triangles(path):
    d = open(path, "rb").read()
    if d[:5] == b"solid" and b"facet" in d[:400]:
        vs = [tuple(map(float, m.groups())) for m in re.finditer(rb"vertex\s+(\S+)\s+(\S+)\s+(\S+)", d)]
        return [vs[i:i + 3] for i in range(0, len(vs), 3)]
    n = struct.unpack("<I", d[80:84])[0]
    out = []
    for i in range(n):
        f = struct.unpack("<12f", d[84 + 50 * i:84 + 50 * i + 48])
        out.append((f[3:6], f[6:9], f[9:12]))
    return out


def volume(path):
    v = 0.0
    for a, b, c in stl_triangles(path):
        v += a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0])
    return abs(v) / 6


def bbox(path):
    pts = [p for t in stl_triangles(path) for p in t]
    return [max(p[k] for p in pts) - min(p[k] for p in pts) for k in range(3)] if pts else [0, 0, 0]


def openscad_stl(model, out, defines=()):
    args = ["openscad", "--quiet", "-o", out]
    for d in defines:
        args += ["-D", d]
    t = time.monotonic()
    r = subprocess.run(args + [model], capture_output=True, text=True)
    return time.monotonic() - t, r.returncode == 0 and os.path.exists(out)


def fabatlas_eval(design, mesh, at=None):
    args = [FABATLAS, "eval", design, "--json", "--mesh", mesh]
    if at:
        args += ["--at", at]
    t = time.monotonic()
    r = subprocess.run(args, capture_output=True, text=True)
    wall = time.monotonic() - t
    if r.returncode != 0 and not r.stdout:
        raise RuntimeError(design + ": " + r.stderr.strip())
    return wall, json.loads(r.stdout)


def speed(repeats):
    tmp = tempfile.mkdtemp(prefix="scad-bench-")
    models = [os.path.join(ROOT, "configs/scad/tray.scad"),
              os.path.join(EXAMPLES, "Parametric/sign.scad"),
              os.path.join(EXAMPLES, "Parametric/candleStand.scad")]
    print("| model | OpenSCAD STL wall s | fabatlas geometry s (ratio) | fabatlas whole sample s (ratio) | volume OpenSCAD / fabatlas mm^3 (diff) |")
    print("|---|---|---|---|---|")
    for model in models:
        name = os.path.basename(model)
        osc, geo, whole = [], [], []
        ref = os.path.join(tmp, name + ".ref.stl")
        ours = os.path.join(tmp, name + ".ours.stl")
        for _ in range(repeats):  # interleaved, so both see the same load
            t, ok = openscad_stl(model, ref)
            if not ok:
                raise RuntimeError(model + ": openscad failed")
            osc.append(t)
            _, j = fabatlas_eval(model, ours)
            geo.append(j["timings"]["tree"])
            whole.append(j["timings"]["total"])
        vo, vf = volume(ref), volume(ours)
        mo, mg, mw = statistics.median(osc), statistics.median(geo), statistics.median(whole)
        print(f"| {name} | {mo:.3f} | {mg:.3f} ({mg / mo:.2f}) | {mw:.3f} ({mw / mo:.2f}) | {vo:.1f} / {vf:.1f} ({100 * (vf - vo) / vo:+.2f}%) |")
    print(f"\nload average: {os.getloadavg()}")


def coverage():
    tmp = tempfile.mkdtemp(prefix="scad-coverage-")
    rows, native_full = [], 0
    models = sorted(glob.glob(os.path.join(EXAMPLES, "*", "*.scad")))
    for model in models:
        rel = os.path.relpath(model, EXAMPLES)
        ref = os.path.join(tmp, "ref.stl")
        if os.path.exists(ref):
            os.remove(ref)
        _, ok = openscad_stl(model, ref)
        if not ok or os.path.getsize(ref) < 100:
            rows.append((rel, "OpenSCAD renders no 3D STL (2D, echo or animation example)", "", ""))
            continue
        size = max(bbox(ref))
        voxel = min(1.0, max(0.1, round(size / 200 / 0.05) * 0.05))
        design = os.path.join(tmp, "d.yaml")
        with open(design, "w") as f:
            f.write(f"name: coverage\nvoxel_size: {voxel}\nparameters: {{unused: {{type: real, min: 0, max: 1}}}}\n"
                    f"tree: {{op: openscad, file: {json.dumps(model)}}}\nproperties: [volume]\n")
        ours = os.path.join(tmp, "ours.stl")
        try:
            _, j = fabatlas_eval(design, ours)
        except Exception as e:
            rows.append((rel, "fabatlas failed: " + str(e)[:120], "", ""))
            continue
        ops = [s["op"] for s in j.get("subtrees", [])]
        native = sum(o.startswith("csg:") for o in ops)
        rendered = [o[len("csg-openscad:"):] for o in ops if o.startswith("csg-openscad:")]
        if not j.get("valid") and not os.path.exists(ours):
            rows.append((rel, "no geometry: " + str(j.get("failure_reason", ""))[:120], native, ",".join(rendered)))
            continue
        vo, vf = volume(ref), volume(ours)
        if not rendered:
            native_full += 1
        rows.append((rel, f"{vo:.1f} / {vf:.1f} ({100 * (vf - vo) / vo:+.2f}%) at voxel {voxel}", native, ",".join(rendered) or "–"))
    print("| example | volume OpenSCAD / fabatlas mm^3 (diff) | native CSG subtrees | rendered by OpenSCAD |")
    print("|---|---|---|---|")
    for r in rows:
        print("| " + " | ".join(str(x) for x in r) + " |")
    print(f"\n{native_full} of {len(models)} examples evaluate fully natively; load average {os.getloadavg()}")


if __name__ == "__main__":
    if len(sys.argv) > 1 and sys.argv[1] == "coverage":
        coverage()
    else:
        repeats = int(sys.argv[sys.argv.index("--repeats") + 1]) if "--repeats" in sys.argv else 3
        speed(repeats)
