#!/usr/bin/env python3
"""fabatlas against OpenSCAD 2021.01 on OpenSCAD's own corpus (docs/openscad.md,
"Coverage on OpenSCAD's own corpus"; the acceptance of the mesh road).

The corpus: every `.scad` in Debian's openscad-testing-data 3D/features,
3D/issues and 3D/misc (/usr/share/openscad/testdata/scad/3D) and in
openscad-mcad (/usr/share/openscad/libraries/MCAD), rendered where it lies
(models include and import their siblings).

The peer: `openscad -o PEER.stl MODEL` (OpenSCAD 2021.01), limited to
--timeout seconds. Its outcome (status, wall time, STL, triangles, enclosed
volume) is cached on disk under --cache, keyed by SHA-256 of the model's bytes
and OpenSCAD's version (files the model includes are not in the key), so a
rerun renders nothing it has rendered. Status: `ok` (an STL enclosing a
positive volume), `empty` (no STL, no triangles or no volume: library files
with nothing at top level, 2-D results, echo tests), `inverted` (an STL whose
triangles enclose a negative volume: OpenSCAD kept a polyhedron's inward
faces), `error` (OpenSCAD failed with another message), `timeout`. The `ok` models are the denominator.

fabatlas: each denominator model evaluated at its own values by a one-node
design beside nothing else,

    name: corpus
    voxel_size: V        # the import's rule: the model's largest edge / 150,
                         # within [0.5, 0.6] mm (docs/openscad.md, "Voxel size")
    parameters: {unused: {type: real, min: 0, max: 1}}
    tree: {op: openscad, file: /abs/MODEL.scad}
    properties: [volume]

and `fabatlas eval DESIGN.yaml --json --mesh OURS.off` (OFF keeps doubles; a float32 STL would round a 5e-6 mm^3 sliver by 0.7%) (limited to
--timeout seconds). `fabatlas eval MODEL.scad` itself imports the model's
Customizer parameters and declines a model that has none ("no Customizer
parameter has a slider or dropdown annotation"), which is most of the corpus;
the design above is the command that evaluates any model at its own values.
The model's largest edge is taken from OpenSCAD's STL (the import measures it
with a coarse evaluation of its own); --voxel MM fixes it instead.

Per model: geometry (a mesh with triangles), the volume's relative error
against OpenSCAD's STL, and the surface distance both ways, from
bench_mesh_compare (bench/scad/mesh_compare.cc: 20,000 area-weighted random
points on each mesh, exact distance to the other's triangles, seeded; p50,
p95, max), fabatlas's and OpenSCAD's wall times. A model passes when it has
geometry, its volume is within 0.1% and p95 <= 0.01 mm both ways.

With --manifold, each denominator model is also evaluated by Manifold
(bench/scad/manifold_csg.mjs: npm manifold-3d, WASM, one thread, the same
.csg tree with OpenSCAD's faceting; median ms in process of 5 after a
warm-up) and measured the same way: what an exact mesh kernel gives on this
corpus, and which nodes the script does not evaluate.

  nice -n 10 python3 bench/scad/corpus.py --jobs 2 --markdown
  nice -n 10 python3 bench/scad/corpus.py --peer-only --jobs 2   # fill the cache only

Writes OUT/corpus.json (every model) and, with --markdown, OUT/corpus.md
(summary and the table of models that do not pass, also printed).
"""
import argparse, concurrent.futures, hashlib, json, os, re, signal, statistics, subprocess, sys, threading, time

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
TESTDATA = "/usr/share/openscad/testdata/scad/3D"
MCAD = "/usr/share/openscad/libraries/MCAD"
CORPUS = [(os.path.join(TESTDATA, d), "3D/" + d) for d in ("features", "issues", "misc")] + [(MCAD, "MCAD")]
VOLUME_TOLERANCE = 1e-3  # relative
P95_TOLERANCE = 0.01     # mm


def corpus_models():
    """(name, absolute path) of every model, sorted by name."""
    models = []
    for directory, label in CORPUS:
        if not os.path.isdir(directory):
            sys.exit(f"corpus.py: {directory} is missing (Debian's openscad-testing-data and openscad-mcad, "
                     "ops/install-deps.sh)")
        for f in sorted(os.listdir(directory)):
            if f.endswith(".scad"):
                models.append((f"{label}/{f}", os.path.join(directory, f)))
    return models


def last_line(text, default=""):
    lines = [l.strip() for l in (text or "").splitlines() if l.strip()]
    return lines[-1][:300] if lines else default


def run(args, timeout, cwd=None):
    """(wall seconds, CompletedProcess or None on timeout). The program runs in
    a session of its own, so a timeout ends what it started too (fabatlas's
    OpenSCAD subtree renders)."""
    t = time.monotonic()
    p = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=cwd, errors="replace",
                         start_new_session=True)
    try:
        out, err = p.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(p.pid, signal.SIGKILL)
        p.communicate()
        return time.monotonic() - t, None
    return time.monotonic() - t, subprocess.CompletedProcess(args, p.returncode, out, err)


class MeshCompare:
    """bench_mesh_compare: volumes of closed meshes and the surface distance between two."""

    def __init__(self, path, samples, seed):
        self.path, self.samples, self.seed = path, samples, seed

    def available(self):
        return os.path.isfile(self.path) and os.access(self.path, os.X_OK)

    def __call__(self, *meshes):
        args = [self.path, *meshes, "--samples", str(self.samples), "--seed", str(self.seed)]
        _, r = run(args, timeout=600)
        if r is None:
            raise RuntimeError("bench_mesh_compare took over 600 s")
        if r.returncode != 0:
            raise RuntimeError(last_line(r.stderr, f"bench_mesh_compare exit {r.returncode}"))
        return json.loads(r.stdout)


# ---- the peer: OpenSCAD 2021.01, cached by the model's bytes ----

def openscad_version():
    _, r = run(["openscad", "--version"], timeout=60)
    if r is None or r.returncode != 0:
        sys.exit("corpus.py: cannot run `openscad --version` (Debian's openscad, ops/install-deps.sh)")
    return last_line(r.stderr + r.stdout)


def peer(model, cache, version, timeout, compare):
    """OpenSCAD's outcome for `model`, rendered once per (bytes, version)."""
    with open(model, "rb") as f:
        key = hashlib.sha256(version.encode() + b"\0" + f.read()).hexdigest()
    entry = os.path.join(cache, key[:2], key)
    meta_path = os.path.join(entry, "peer.json")
    stl = os.path.join(entry, "peer.stl")
    meta = None
    if os.path.exists(meta_path):
        with open(meta_path) as f:
            meta = json.load(f)
        if meta["status"] == "timeout" and meta["timeout"] < timeout:
            meta = None  # a longer limit was asked for: render again
    if meta is None:
        os.makedirs(entry, exist_ok=True)
        if os.path.exists(stl):
            os.remove(stl)
        wall, r = run(["openscad", "-o", stl, model], timeout, cwd=os.path.dirname(model))
        meta = {"model": model, "openscad": version, "wall": round(wall, 3), "timeout": timeout}
        if r is None:
            meta.update(status="timeout", message=f"OpenSCAD took over {timeout} s")
        elif r.returncode != 0 or not os.path.exists(stl):
            msg = last_line(r.stderr, f"exit {r.returncode}")
            empty = re.search(r"top level object is (empty|not a 3D object)|Current top level object is empty", r.stderr)
            meta.update(status="empty" if empty else "error", message=msg)
        else:
            meta.update(status="rendered", message=last_line(r.stderr))
        with open(meta_path + ".tmp", "w") as f:
            json.dump(meta, f, indent=1)
        os.replace(meta_path + ".tmp", meta_path)
    if meta["status"] == "rendered" and "volume" not in meta and compare.available():
        # The STL's volume by the same code as fabatlas's (enclosed_volume.h).
        try:
            v = compare(stl)["meshes"][0]
            meta.update(triangles=v["triangles"], volume=v["volume"], size=v["size"])
        except RuntimeError as e:
            meta.update(triangles=0, volume=0.0, size=[0, 0, 0], volume_message=str(e))
        with open(meta_path + ".tmp", "w") as f:
            json.dump(meta, f, indent=1)
        os.replace(meta_path + ".tmp", meta_path)
    meta = dict(meta, stl=stl)
    if meta["status"] == "rendered" and "volume" in meta:
        v = meta["volume"]
        meta["status"] = "ok" if v > 0 else "inverted" if v < 0 else "empty"
        if meta["status"] != "ok":
            meta["message"] = meta.get("volume_message") or f"the STL encloses {v:g} mm^3"
    return meta


# ---- fabatlas ----

def voxel_for(size, fixed):
    """The import's rule (docs/openscad.md, "Voxel size"): size / 150 within [0.5, 0.6] mm, to 0.05 mm."""
    if fixed:
        return fixed
    return min(0.6, max(0.5, round(size / 150 / 0.05) * 0.05))


def fabatlas(name, model, fab, work, timeout, voxel, size):
    d = os.path.join(work, re.sub(r"[^A-Za-z0-9_.-]", "_", name))
    os.makedirs(d, exist_ok=True)
    design, ours = os.path.join(d, "design.yaml"), os.path.join(d, "ours.off")  # doubles: a float STL rounds slivers
    if os.path.exists(ours):
        os.remove(ours)
    v = voxel_for(size, voxel)
    with open(design, "w") as f:
        f.write(f"name: corpus\nvoxel_size: {v}\nparameters: {{unused: {{type: real, min: 0, max: 1}}}}\n"
                f"tree: {{op: openscad, file: {json.dumps(model)}}}\nproperties: [volume]\n")
    wall, r = run([fab, "eval", design, "--json", "--mesh", ours], timeout, cwd=d)
    out = {"voxel": v, "wall": round(wall, 3), "mesh": ours}
    if r is None:
        return dict(out, geometry=False, message=f"fabatlas took over {timeout} s")
    try:
        j = json.loads(r.stdout) if r.stdout.strip() else {}
    except json.JSONDecodeError:
        j = {}
    if j:
        out["sample_seconds"] = j.get("timings", {}).get("total")
        ops = [s.get("op", "") for s in j.get("subtrees", [])]
        out["rendered_by_openscad"] = sorted({o[len("csg-openscad:"):] for o in ops if o.startswith("csg-openscad:")})
    ok = r.returncode == 0 and os.path.exists(ours) and os.path.getsize(ours) > 84
    if not ok:
        msg = last_line(r.stderr) or f"exit {r.returncode}"
        if not j and "has no geometry to write" in msg:
            # --mesh refuses an empty sample before printing it: the sample's
            # own failure, from the same evaluation without --mesh.
            _, r2 = run([fab, "eval", design, "--json"], timeout, cwd=d)
            try:
                j2 = json.loads(r2.stdout) if r2 is not None and r2.stdout.strip() else {}
            except json.JSONDecodeError:
                j2 = {}
            msg = str(j2.get("failure_reason") or j2.get("failure") or msg)
        return dict(out, geometry=False, message=msg.replace(model + ": ", ""))
    return dict(out, geometry=True)


def manifold(name, model, work, timeout, compare, peer_stl, peer_volume):
    d = os.path.join(work, re.sub(r"[^A-Za-z0-9_.-]", "_", name))
    os.makedirs(d, exist_ok=True)
    stl = os.path.join(d, "manifold.stl")
    if os.path.exists(stl):
        os.remove(stl)
    # --single-threaded: V8 without its worker threads (compilation, GC): the
    # one thread the comparison is about.
    wall, r = run(["node", "--single-threaded", os.path.join(ROOT, "bench", "scad", "manifold_csg.mjs"), model, "--json", "--stl", stl],
                  timeout, cwd=os.path.dirname(model))
    if r is None:
        return {"geometry": False, "message": f"took over {timeout} s"}
    try:
        j = json.loads(r.stdout.strip().splitlines()[-1])
    except (json.JSONDecodeError, IndexError):
        return {"geometry": False, "message": last_line(r.stderr, f"exit {r.returncode}")}
    out = {"outlined_by_openscad": j.get("outlined_by_openscad", [])}
    if "ms_median" not in j:
        msg = ("not evaluated: " + ", ".join(j["unsupported"])) if j.get("unsupported") else j.get("error", "?")
        return dict(out, geometry=False, message=msg)
    out.update(ms=j["ms_median"], triangles=j["triangles"], volume=j["volume"])
    if j["triangles"] == 0:
        return dict(out, geometry=False, message="no triangles")
    c = compare(peer_stl, stl)
    out.update(geometry=True, volume_error=(c["meshes"][1]["volume"] - peer_volume) / peer_volume,
               distance={"openscad_to_manifold": c["distance"]["a_to_b"], "manifold_to_openscad": c["distance"]["b_to_a"]})
    return out


def evaluate(name, model, a, cache, version, compare, lock, done, total):
    p = peer(model, cache, version, a.timeout, compare)
    row = {"model": name, "path": model,
           "openscad": {k: p.get(k) for k in ("status", "wall", "volume", "triangles", "message")}}
    if a.peer_only or p["status"] != "ok":
        pass
    else:
        f = fabatlas(name, model, a.fabatlas, os.path.join(a.out, "models"), a.timeout, a.voxel, max(p["size"]))
        row["fabatlas"] = {k: f.get(k) for k in ("geometry", "wall", "sample_seconds", "voxel", "message",
                                                 "rendered_by_openscad") if k in f}
        if f["geometry"]:
            try:
                c = compare(p["stl"], f["mesh"])
                vo, vf = c["meshes"][0]["volume"], c["meshes"][1]["volume"]
                row["fabatlas"].update(volume=vf, triangles=c["meshes"][1]["triangles"])
                row["volume_error"] = (vf - vo) / vo
                row["distance"] = {"openscad_to_fabatlas": c["distance"]["a_to_b"],
                                   "fabatlas_to_openscad": c["distance"]["b_to_a"]}
            except RuntimeError as e:
                row["fabatlas"].update(geometry=False, message=f"its mesh could not be measured: {e}")
        row["passes"] = passes(row)
        if a.manifold:
            try:
                row["manifold"] = manifold(name, model, os.path.join(a.out, "models"), a.timeout, compare, p["stl"],
                                           p["volume"])
            except RuntimeError as e:
                row["manifold"] = {"geometry": False, "message": str(e)}
    with lock:
        done[0] += 1
        f = row.get("fabatlas")
        state = p["status"] if f is None else ("pass" if row["passes"] else "FAIL: " + reason(row))
        print(f"[{done[0]}/{total}] {name}: OpenSCAD {p['status']} {p['wall']:.1f} s; {state}", file=sys.stderr, flush=True)
    return row


def passes(row):
    f = row.get("fabatlas", {})
    if not f.get("geometry"):
        return False
    d = row.get("distance", {})
    return (abs(row["volume_error"]) <= VOLUME_TOLERANCE and
            all(d[k]["p95"] <= P95_TOLERANCE for k in ("openscad_to_fabatlas", "fabatlas_to_openscad")))


def reason(row):
    f = row["fabatlas"]
    if not f.get("geometry"):
        return "no geometry: " + (f.get("message") or "")
    out = []
    if abs(row["volume_error"]) > VOLUME_TOLERANCE:
        out.append(f"volume {100 * row['volume_error']:+.2f}%")
    d = row["distance"]
    p1, p2 = d["openscad_to_fabatlas"]["p95"], d["fabatlas_to_openscad"]["p95"]
    if max(p1, p2) > P95_TOLERANCE:
        out.append(f"p95 {p1:.3g} / {p2:.3g} mm")
    return ", ".join(out)


def summarise(rows):
    peer_counts = {}
    for r in rows:
        peer_counts[r["openscad"]["status"]] = peer_counts.get(r["openscad"]["status"], 0) + 1
    den = [r for r in rows if "fabatlas" in r]
    geo = [r for r in den if r["fabatlas"].get("geometry")]
    vol = [r for r in geo if abs(r["volume_error"]) <= VOLUME_TOLERANCE]
    near = [r for r in geo if max(r["distance"][k]["p95"] for k in r["distance"]) <= P95_TOLERANCE]
    pct = lambda n: round(100 * n / len(den), 1) if den else None
    p95s = sorted(max(r["distance"][k]["p95"] for k in r["distance"]) for r in geo)
    fw = [r["fabatlas"]["wall"] for r in den]
    ow = [r["openscad"]["wall"] for r in den]
    mf = [r["manifold"] for r in den if "manifold" in r]
    mf_geo = [m for m in mf if m.get("geometry")]
    manifold = {
        "evaluated": len(mf), "geometry": len(mf_geo),
        "volume_within_0.1pct": sum(abs(m["volume_error"]) <= VOLUME_TOLERANCE for m in mf_geo),
        "p95_within_0.01mm": sum(max(m["distance"][k]["p95"] for k in m["distance"]) <= P95_TOLERANCE for m in mf_geo),
        "ms_median": statistics.median(m["ms"] for m in mf_geo) if mf_geo else None,
    } if mf else None
    return {
        "manifold": manifold,
        "models": len(rows), "openscad": peer_counts, "denominator": len(den),
        "geometry": len(geo), "geometry_pct": pct(len(geo)),
        "volume_within_0.1pct": len(vol), "volume_pct": pct(len(vol)),
        "p95_within_0.01mm": len(near), "p95_pct": pct(len(near)),
        "pass": sum(r["passes"] for r in den),
        "p95_worse_way_median_mm": statistics.median(p95s) if p95s else None,
        "p95_worse_way_max_mm": p95s[-1] if p95s else None,
        "fabatlas_wall_median_s": statistics.median(fw) if fw else None,
        "openscad_wall_median_s": statistics.median(ow) if ow else None,
    }


def markdown(summary, rows, command):
    s = summary
    peer = ", ".join(f"{n} {k}" for k, n in sorted(s["openscad"].items()))
    lines = [f"Command: `{command}`", "",
             f"{s['models']} models; OpenSCAD 2021.01: {peer} (`ok` = an STL with positive volume: the denominator).", "",
             "| models (OpenSCAD STL with volume) | give geometry | volume within 0.1% | p95 <= 0.01 mm both ways | all three |",
             "|---|---|---|---|---|",
             f"| {s['denominator']} | {s['geometry']} ({s['geometry_pct']}%) | {s['volume_within_0.1pct']} ({s['volume_pct']}%) "
             f"| {s['p95_within_0.01mm']} ({s['p95_pct']}%) | {s['pass']} |", "",
             f"p95 (the worse way) over models with geometry: median {fmt(s['p95_worse_way_median_mm'])} mm, "
             f"max {fmt(s['p95_worse_way_max_mm'])} mm. Wall time per model, median: fabatlas "
             f"{fmt(s['fabatlas_wall_median_s'])} s, OpenSCAD {fmt(s['openscad_wall_median_s'])} s.", "",
             "| model | why | volume OpenSCAD / fabatlas mm^3 | p95 OpenSCAD→fabatlas / fabatlas→OpenSCAD mm (max) | wall fabatlas / OpenSCAD s |",
             "|---|---|---|---|---|"]
    for r in rows:
        if "fabatlas" not in r or r["passes"]:
            continue
        f, o = r["fabatlas"], r["openscad"]
        vol = f"{o['volume']:.6g} / {f['volume']:.6g}" if f.get("geometry") else f"{o['volume']:.6g} / –"
        if f.get("geometry"):
            a, b = r["distance"]["openscad_to_fabatlas"], r["distance"]["fabatlas_to_openscad"]
            dist = f"{a['p95']:.3g} / {b['p95']:.3g} ({max(a['max'], b['max']):.3g})"
        else:
            dist = "–"
        why = reason(r).replace("|", "\\|")
        lines.append(f"| {r['model']} | {why} | {vol} | {dist} | {f['wall']:.2f} / {o['wall']:.2f} |")
    if s.get("manifold"):
        m = s["manifold"]
        lines += ["", f"Manifold (bench/scad/manifold_csg.mjs) on the same {m['evaluated']} models: geometry {m['geometry']}, "
                  f"volume within 0.1% {m['volume_within_0.1pct']}, p95 <= 0.01 mm both ways {m['p95_within_0.01mm']}; "
                  f"in-process evaluation median {fmt(m['ms_median'])} ms.", "",
                  "| model | Manifold: why not |", "|---|---|"]
        for r in rows:
            mm = r.get("manifold")
            if not mm:
                continue
            if not mm.get("geometry"):
                why = mm.get("message", "")
            else:
                p1, p2 = (mm["distance"][k]["p95"] for k in ("openscad_to_manifold", "manifold_to_openscad"))
                why = ", ".join(x for x in (f"volume {100 * mm['volume_error']:+.3f}%" if abs(mm["volume_error"]) > VOLUME_TOLERANCE else "",
                                            f"p95 {p1:.3g} / {p2:.3g} mm" if max(p1, p2) > P95_TOLERANCE else "") if x)
            if why:
                lines.append(f"| {r['model']} | {why.replace('|', '/')} |")
    lines += ["", "Not in the denominator (OpenSCAD gives no STL with volume):", ""]
    for r in rows:
        if r["openscad"]["status"] not in ("ok",):
            lines.append(f"- {r['model']}: {r['openscad']['status']}: {(r['openscad'].get('message') or '').replace('|', '/')}")
    return "\n".join(lines) + "\n"


def fmt(x):
    return "–" if x is None else f"{x:.3g}"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--fabatlas", default=os.path.join(ROOT, "build", "bin", "fabatlas"))
    ap.add_argument("--mesh-compare", default=None,
                    help="bench_mesh_compare (default: beside --fabatlas)")
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--filter", default=None, help="regular expression on the model's name, e.g. 'issues/|MCAD'")
    ap.add_argument("--out", default=os.path.join(ROOT, "build", "scad-corpus"))
    ap.add_argument("--cache", default=os.path.join(os.path.expanduser("~"), ".cache", "fabatlas", "openscad-corpus"),
                    help="OpenSCAD's renders, keyed by the model's bytes and OpenSCAD's version")
    ap.add_argument("--timeout", type=float, default=300, help="seconds per program run (OpenSCAD, fabatlas)")
    ap.add_argument("--voxel", type=float, default=0, help="level-set voxel in mm (default: the import's rule)")
    ap.add_argument("--samples", type=int, default=20000)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--peer-only", action="store_true", help="only render (and cache) OpenSCAD's STLs")
    ap.add_argument("--markdown", action="store_true", help="write OUT/corpus.md and print it")
    ap.add_argument("--manifold", action="store_true",
                    help="also evaluate each model with Manifold (bench/scad/manifold_csg.mjs, npm manifold-3d)")
    a = ap.parse_args()
    a.fabatlas = os.path.abspath(a.fabatlas)
    a.out = os.path.abspath(a.out)
    compare = MeshCompare(a.mesh_compare or os.path.join(os.path.dirname(a.fabatlas), "bench_mesh_compare"),
                          a.samples, a.seed)
    if not a.peer_only:
        for exe, what in ((a.fabatlas, "--fabatlas"), (compare.path, "--mesh-compare")):
            if not (os.path.isfile(exe) and os.access(exe, os.X_OK)):
                sys.exit(f"corpus.py: {what} {exe} is not an executable (build it, or name it)")
    models = corpus_models()
    if a.filter:
        models = [m for m in models if re.search(a.filter, m[0])]
    os.makedirs(a.out, exist_ok=True)
    os.makedirs(a.cache, exist_ok=True)
    version = openscad_version()
    lock, done = threading.Lock(), [0]
    with concurrent.futures.ThreadPoolExecutor(max_workers=max(1, a.jobs)) as pool:
        rows = list(pool.map(lambda m: evaluate(m[0], m[1], a, a.cache, version, compare, lock, done, len(models)),
                             models))
    summary = summarise(rows)
    command = "python3 bench/scad/corpus.py " + " ".join(sys.argv[1:])
    result = {"command": command, "openscad": version, "fabatlas": a.fabatlas, "load_average": os.getloadavg(),
              "finished_utc": time.strftime("%Y-%m-%d %H:%M", time.gmtime()), "summary": summary, "models": rows}
    with open(os.path.join(a.out, "corpus.json"), "w") as f:
        json.dump(result, f, indent=1)
    if a.markdown and not a.peer_only:
        md = markdown(summary, rows, command)
        with open(os.path.join(a.out, "corpus.md"), "w") as f:
            f.write(md)
        print(md)
    s = summary
    print(f"{s['models']} models, OpenSCAD {s['openscad']}; of {s['denominator']} with an STL with volume: "
          f"geometry {s['geometry_pct']}%, volume within 0.1% {s['volume_pct']}%, p95 <= 0.01 mm both ways "
          f"{s['p95_pct']}% ({a.out}/corpus.json)")


if __name__ == "__main__":
    main()
