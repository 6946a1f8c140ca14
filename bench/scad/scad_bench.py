#!/usr/bin/env python3
"""OpenSCAD models through fabatlas against OpenSCAD itself (docs/openscad.md).

  bench/scad/scad_bench.py speed [--repeats 3] [--manifold]   tray, sign.scad, candleStand.scad:
      OpenSCAD's own STL render wall time vs one fabatlas sample of
      `fabatlas eval MODEL.scad` (imported on the fly, automatic voxel):
      geometry (the model's CSG tree, by fabatlas's own evaluation or
      OpenSCAD's .csg export, + its level sets: timings.tree), the whole
      sample (a worker's cost for one point: geometry, properties and the
      imported design's checks, timings.total) and the eval process's wall
      time (import, model measurement, sample, mesh export); a worker's
      sample (the model's default point evaluated 10 times in one process by
      bench_design_samples, beside fabatlas: the median wall time of those
      samples, what each sample of a job costs once the process has
      evaluated one, against the first sample of a fresh process that
      `fabatlas eval` times); then where the
      whole sample goes (CSG tree, level sets, properties, the surface the
      checks read, each check: they run side by side, so their times
      overlap); the CPU seconds (user + system) of the OpenSCAD and the eval
      processes;
      medians of --repeats, interleaved; volumes of OpenSCAD's STL, of the
      sample's `volume` property and of the mesh fabatlas exports. With
      --manifold, a last column: Manifold (npm manifold-3d, WASM, one thread)
      evaluating the same .csg tree in process (bench/scad/manifold_csg.mjs:
      median of max(5, --repeats) after a warm-up, WASM start-up excluded),
      its volume, and its time over fabatlas's whole sample.
  bench/scad/scad_bench.py job [--samples tray=40,sign=40,candleStand=24] [--repeats 5] [--keep DIR]
      the goal's own metric (issue 30): a job's mean sample cost, with the
      subtree cache, as a job runs, against Manifold on the same points. Each
      model is imported (`fabatlas import-scad`, its own exposed parameters
      and job file; only sampling.max_samples set to --samples) and run as a
      job runs, `fabatlas run JOB --workers 1 --out DIR` (one worker, one
      slot: its TBB loops run on the task's thread, so a task's thread CPU is
      all of its CPU). The run's own figures: each task's TaskResult in the
      job store (DIR/cluster-state/state.db) carries the worker's wall and
      thread CPU seconds of the evaluator call (in process: geometry with the
      worker's subtree cache, properties and checks; no process start) and,
      for a sample, its subtree records (op, seconds, from_cache: where the
      sample's time goes); statistics.json the evaluator total (samples and
      ΔG). Then, for every sample point of the run, Manifold
      (bench/scad/manifold_csg.mjs: OpenSCAD 2021 writes the .csg with the
      point's -D values, untimed; one thread, WASM start-up excluded; the
      median of max(5, --repeats) in process after a warm-up) and its mean
      over the same points, beside fabatlas's in-process mean. Also the
      run's process wall and the CPU of its processes (coordinator, worker;
      start-up, ΔG tasks included). --keep DIR keeps the imports and runs.
      A job's ΔG tasks cost more than its samples (docs/openscad.md, "The
      speed goal as a job runs"): at the default budgets the sign and
      candleStand jobs take 20 minutes or more on a loaded machine; a run
      stopped early keeps its finished samples' figures in its store.
  bench/scad/scad_bench.py coverage [--timeout 120]   every example Debian's
      openscad ships: does `import-scad` take it (and why not), is it
      evaluated fully natively or with subtrees OpenSCAD rendered, the volume
      difference to OpenSCAD's own STL; each program run limited to
      --timeout seconds; rows are printed as they finish. The voxel is about
      1/150 of the model (within [0.1, 1] mm); where the volume differs by
      more than 1% the example is evaluated again at half the voxel (down to
      0.1 mm, three times at most), which tells features thinner than the voxel
      (the difference shrinks) from wrong geometry (it stays).

Run from the repository root with build/bin/fabatlas built, under nice.
Volumes of meshes are those their surfaces enclose (divergence theorem over
the STL triangles).
"""
import json, os, re, resource, shutil, statistics, struct, subprocess, sys, tempfile, time, glob

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
FABATLAS = os.environ.get("FABATLAS_BIN", os.path.join(ROOT, "build", "bin", "fabatlas"))
EXAMPLES = "/usr/share/openscad/examples"
DESIGN_SAMPLES = os.environ.get("BENCH_DESIGN_SAMPLES_BIN",
                                os.path.join(os.path.dirname(FABATLAS), "bench_design_samples"))


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


def children_cpu():
    """User + system CPU seconds of the finished child processes so far."""
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def openscad_stl(model, out, defines=(), timeout=None):
    args = ["openscad", "--quiet", "-o", out]
    for d in defines:
        args += ["-D", d]
    t = time.monotonic()
    try:
        r = subprocess.run(args + [model], capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return time.monotonic() - t, False
    return time.monotonic() - t, r.returncode == 0 and os.path.exists(out)


def fabatlas_eval(design, mesh, at=None, timeout=None):
    args = [FABATLAS, "eval", design, "--json", "--mesh", mesh]
    if at:
        args += ["--at", at]
    t = time.monotonic()
    r = subprocess.run(args, capture_output=True, text=True, timeout=timeout)
    wall = time.monotonic() - t
    if r.returncode != 0 and not r.stdout:
        raise RuntimeError((r.stderr.strip().splitlines() or ["exit %d" % r.returncode])[-1])
    return wall, json.loads(r.stdout)


def pct(a, b):
    return 100 * (a - b) / b


def manifold_csg(model, repeats):
    """(median ms, volume) of bench/scad/manifold_csg.mjs evaluating the model's .csg tree."""
    r = subprocess.run(["node", "--single-threaded", os.path.join(ROOT, "bench", "scad", "manifold_csg.mjs"), model, "--json",
                        "--repeats", str(max(5, repeats))], capture_output=True, text=True)
    j = json.loads(r.stdout.strip().splitlines()[-1]) if r.stdout.strip() else {}
    if "ms_median" not in j:
        raise RuntimeError(model + ": manifold_csg: " + (j.get("error") or ", ".join(j.get("unsupported", []))
                                                         or r.stderr.strip()[-200:]))
    return j["ms_median"], j["volume"]


def speed(repeats, manifold=False):
    tmp = tempfile.mkdtemp(prefix="scad-bench-")
    models = [os.path.join(ROOT, "configs/scad/tray.scad"),
              os.path.join(EXAMPLES, "Parametric/sign.scad"),
              os.path.join(EXAMPLES, "Parametric/candleStand.scad")]
    breakdown = []
    print("| model | voxel mm | OpenSCAD STL wall s (process CPU) | fabatlas geometry s (ratio) | whole sample s (ratio) | a worker's sample s (ratio) | eval process wall s (process CPU) | volume OpenSCAD / property (diff) / mesh (diff) mm^3 |"
          + (" Manifold in process ms, volume (diff); whole sample / Manifold |" if manifold else ""))
    print("|---|---|---|---|---|---|---|---|" + ("---|" if manifold else ""))
    for model in models:
        name = os.path.basename(model)
        osc, geo, whole, steady, walls, osc_cpu, eval_cpu = [], [], [], [], [], [], []
        design = os.path.join(tmp, name + ".yaml")
        subprocess.run([FABATLAS, "import-scad", model, "--out", design], capture_output=True)
        parts = {}  # where the whole sample goes: seconds per part, per run
        ref = os.path.join(tmp, name + ".ref.stl")
        ours = os.path.join(tmp, name + ".ours.stl")
        j = None
        for _ in range(repeats):  # interleaved, so both see the same load
            c = children_cpu()
            t, ok = openscad_stl(model, ref)
            if not ok:
                raise RuntimeError(model + ": openscad failed")
            osc.append(t)
            osc_cpu.append(children_cpu() - c)
            c = children_cpu()
            w, j = fabatlas_eval(model, ours)
            eval_cpu.append(children_cpu() - c)
            walls.append(w)
            geo.append(j["timings"]["tree"])
            whole.append(j["timings"]["total"])
            tree = {r["op"]: r["seconds"] for r in j.get("subtrees", []) if r["op"] == "openscad"}
            run_parts = {"CSG tree (native or .csg export)": tree.get("openscad", float("nan")),
                         "level sets": j["timings"]["tree"] - tree.get("openscad", 0.0),
                         "properties": j["timings"].get("properties", 0.0),
                         "surface (extracted once for the checks)": j["timings"].get("surface", 0.0)}
            for check, c in j["checks"].items():
                if check not in ("geometry", "constraints"):
                    run_parts[check] = c["seconds"]
            for k, v in run_parts.items():
                parts.setdefault(k, []).append(v)
            if os.path.exists(DESIGN_SAMPLES) and os.path.exists(design):
                r = subprocess.run([DESIGN_SAMPLES, "--defaults", "10", design], capture_output=True, text=True)
                # The median wall s of the valid samples, to 0.1 ms ("stages" line).
                total = re.search(r"stages \(.*? total ([0-9.]+),", r.stdout)
                if total:
                    steady.append(float(total.group(1)))
        vo, vm, vp = volume(ref), volume(ours), j["properties"].get("volume", float("nan"))
        voxel = ""
        if os.path.exists(design):
            voxel = re.search(r"voxel_size: (\S+)", open(design).read()).group(1)
        mo, mg, mw, mp, co, ce = (statistics.median(x) for x in (osc, geo, whole, walls, osc_cpu, eval_cpu))
        ms = f"{statistics.median(steady):.4f} ({statistics.median(steady) / mo:.3f})" if steady else "n/a"
        mf = ""
        if manifold:
            m_ms, m_vol = manifold_csg(model, repeats)
            mf = f" {m_ms:.1f}, {m_vol:.1f} ({pct(m_vol, vo):+.4f}%); {1000 * mw / m_ms:.2f}x |"
        print(f"| {name} | {voxel} | {mo:.3f} (CPU {co:.3f}) | {mg:.3f} ({mg / mo:.2f}) | {mw:.4f} ({mw / mo:.3f}) | {ms} | {mp:.3f} (CPU {ce:.3f}) | "
              f"{vo:.1f} / {vp:.1f} ({pct(vp, vo):+.2f}%) / {vm:.1f} ({pct(vm, vo):+.2f}%) |" + mf, flush=True)
        breakdown.append(f"{name}: " + ", ".join(f"{k} {statistics.median(v):.3f}" for k, v in parts.items()))
    print("\nwhere the whole sample goes (medians, s; the checks run side by side after the surface, so their"
          " times overlap):")
    for line in breakdown:
        print("- " + line)
    print(f"\nload average: {os.getloadavg()}")


# ---- job: a job's mean sample cost against Manifold on the same points ----

JOB_MODELS = {"tray": os.path.join(ROOT, "configs/scad/tray.scad"),
              "sign": os.path.join(EXAMPLES, "Parametric/sign.scad"),
              "candleStand": os.path.join(EXAMPLES, "Parametric/candleStand.scad")}


def protobuf_fields(buf):
    """(field number, value) of one protobuf message's top-level fields, in
    order (Protocol Buffers encoding: varints as int, length-delimited as
    bytes, fixed64 as 8 bytes, fixed32 as 4 bytes)."""
    i, out = 0, []

    def varint():
        nonlocal i
        v = shift = 0
        while True:
            b = buf[i]
            i += 1
            v |= (b & 0x7F) << shift
            shift += 7
            if b < 0x80:
                return v

    while i < len(buf):
        tag = varint()
        field, wire = tag >> 3, tag & 7
        if wire == 0:
            out.append((field, varint()))
        elif wire == 1:
            out.append((field, buf[i:i + 8]))
            i += 8
        elif wire == 2:
            n = varint()
            out.append((field, buf[i:i + n]))
            i += n
        elif wire == 5:
            out.append((field, buf[i:i + 4]))
            i += 4
        else:
            raise ValueError(f"protobuf wire type {wire} not read here")
    return out


def f64(b):
    return struct.unpack("<d", b)[0]


def sample_tasks(state_db):
    """The sample tasks of a finished run, in the order the job made them,
    from its job store (tasks.proto: TaskPayload, TaskResult): u, wall and
    thread CPU seconds of the evaluator call, valid, failure, volume, subtree
    records (op, topology, seconds, from_cache)."""
    import sqlite3
    db = sqlite3.connect(f"file:{state_db}?mode=ro", uri=True)
    rows = db.execute("SELECT kind, payload, result FROM tasks WHERE result IS NOT NULL ORDER BY seq").fetchall()
    samples, others = [], {"cpu": 0.0, "wall": 0.0, "n": 0}
    for kind, payload, result in rows:
        res = dict()
        subtrees = []
        for f, v in protobuf_fields(result):
            if f == 1:
                sample = {"valid": False, "failure": "", "properties": {}}
                for g, w in protobuf_fields(v):
                    if g == 1:
                        sample["valid"] = bool(w)
                    elif g == 2:
                        sample["failure"] = w.decode()
                    elif g == 3:
                        e = dict(protobuf_fields(w))
                        sample["properties"][e.get(1, b"").decode()] = f64(e[2]) if 2 in e else 0.0
                    elif g == 5:
                        rec = {"op": "", "topology": "", "seconds": 0.0, "from_cache": False}
                        for h, x in protobuf_fields(w):
                            if h == 2:
                                rec["topology"] = x.decode()
                            elif h == 3:
                                rec["op"] = x.decode()
                            elif h == 4:
                                rec["seconds"] = f64(x)
                            elif h == 5:
                                rec["from_cache"] = bool(x)
                        subtrees.append(rec)
                res["sample"] = sample
            elif f == 10:
                res["cpu"] = f64(v)
            elif f == 11:
                res["wall"] = f64(v)
        if kind != 1:  # TASK_KIND_SAMPLE
            others["cpu"] += res.get("cpu", 0.0)
            others["wall"] += res.get("wall", 0.0)
            others["n"] += 1
            continue
        u = []
        for f, v in protobuf_fields(payload):
            if f == 2:  # point_a: SamplePoint, u = 2 (packed doubles)
                for g, w in protobuf_fields(v):
                    if g == 2:  # packed, or one double unpacked: 8 bytes each
                        u += [f64(w[k:k + 8]) for k in range(0, len(w), 8)]
        s = res.get("sample", {"valid": False, "failure": "?", "properties": {}})
        samples.append({"u": u, "cpu": res.get("cpu", 0.0), "wall": res.get("wall", 0.0), "valid": s["valid"],
                        "failure": s["failure"], "volume": s["properties"].get("volume"), "subtrees": subtrees})
    return samples, others


def openscad_defines(design, u):
    """The -D name=value of a point u (in the design's exposed order) for the
    design's `openscad` node, as the node passes them (docs/openscad.md, "How
    values reach OpenSCAD"): `set` maps OpenSCAD names to parameters, an enum's
    `choices` give its OpenSCAD values (a string quoted)."""
    import yaml
    params = list(design["parameters"].items())
    tree = design["tree"]
    value = {}
    for (name, p), x in zip(params, u):
        if p["type"] == "enum":
            v = tree.get("choices", {}).get(name, p["values"])[int(round(x))]
            value[name] = ('"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"') if isinstance(v, str) else str(v)
        elif p["type"] == "integer":
            value[name] = str(int(round(x)))
        else:
            value[name] = repr(float(x))
    out = []
    for var, expr in tree.get("set", {}).items():
        if expr not in value:
            raise RuntimeError(f"set {var}: {expr}: only a parameter's own name is passed by this benchmark")
        out.append(f"{var}={value[expr]}")
    return out


def bootstrap_samples(design, subdivisions):
    """Corners of the bootstrap grid (docs/sampling.md): subdivisions + 1
    values per real dimension, min(subdivisions, v - 1) + 1 for one of v
    integer or enumerated values."""
    n = 1
    for p in design["parameters"].values():
        if p["type"] == "enum":
            v = len(p["values"])
        elif p["type"] == "integer":
            v = int(p["max"]) - int(p["min"]) + 1
        else:
            v = subdivisions + 1
        n *= min(subdivisions, v - 1) + 1
    return n


def job(budgets, repeats, keep):
    import yaml
    tmp = keep or tempfile.mkdtemp(prefix="scad-job-")
    os.makedirs(tmp, exist_ok=True)
    rows, notes = [], []
    for name, model in JOB_MODELS.items():
        if name not in budgets:
            continue
        # The model beside its design (with its presets file): a job bundle
        # carries the files under the design's folder, not a path outside it.
        for f in glob.glob(os.path.splitext(model)[0] + ".*"):
            shutil.copy(f, tmp)
        model = os.path.join(tmp, os.path.basename(model))
        design_file = os.path.join(tmp, name + ".yaml")
        subprocess.run([FABATLAS, "import-scad", model, "--out", design_file], capture_output=True, check=True)
        job_file = os.path.join(tmp, name + ".job.yaml")
        text = open(job_file).read()
        design = yaml.safe_load(open(design_file))
        subdivisions = int(re.search(r"subdivisions: (\d+)", text).group(1))
        while subdivisions > 1 and bootstrap_samples(design, subdivisions) > budgets[name]:
            subdivisions -= 1
        text, n = re.subn(r"max_samples: \d+", f"max_samples: {budgets[name]}", text)
        text, m = re.subn(r"subdivisions: \d+", f"subdivisions: {subdivisions}", text)
        if n != 1 or m != 1:
            raise RuntimeError(job_file + ": no sampling.max_samples or subdivisions to set")
        open(job_file, "w").write(text)
        out = os.path.join(tmp, name + ".run")
        if os.path.exists(out):
            raise RuntimeError(out + " exists: a run there would resume it, not measure it")
        c, t = children_cpu(), time.monotonic()
        r = subprocess.run([FABATLAS, "run", job_file, "--workers", "1", "--out", out, "--quiet", "--json"],
                           capture_output=True, text=True)
        run_wall, run_cpu = time.monotonic() - t, children_cpu() - c
        if r.returncode != 0:
            raise RuntimeError(f"{name}: fabatlas run failed: {r.stderr.strip()[-300:]}")
        stats = json.load(open(os.path.join(out, "statistics.json")))
        samples, others = sample_tasks(os.path.join(out, "cluster-state", "state.db"))

        # Manifold at every sample point (each distinct point once).
        peer = {}
        for s in samples:
            key = tuple(s["u"])
            if key in peer:
                continue
            args = ["node", "--single-threaded", os.path.join(ROOT, "bench", "scad", "manifold_csg.mjs"), model,
                    "--json", "--repeats", str(max(5, repeats))]
            for d in openscad_defines(design, s["u"]):
                args += ["-D", d]
            m = subprocess.run(args, capture_output=True, text=True)
            j = json.loads(m.stdout.strip().splitlines()[-1]) if m.stdout.strip() else {}
            peer[key] = (j["ms_median"] / 1000, j["volume"], j["cpu_ms_median"] / 1000) if "ms_median" in j else None
            if peer[key] is None:
                notes.append(f"{name} at {key}: Manifold: {j.get('error') or m.stderr.strip()[-160:]}")
        paired = [s for s in samples if peer[tuple(s["u"])] is not None]
        ours_wall = statistics.mean(s["wall"] for s in paired)
        ours_cpu = statistics.mean(s["cpu"] for s in paired)
        theirs = statistics.mean(peer[tuple(s["u"])][0] for s in paired)
        theirs_cpu = statistics.mean(peer[tuple(s["u"])][2] for s in paired)
        vol = [abs(s["volume"] - peer[tuple(s["u"])][1]) / peer[tuple(s["u"])][1] for s in paired
               if s["volume"] and peer[tuple(s["u"])][1] > 0]
        rows.append(f"| {name} | {len(samples)} ({sum(s['valid'] for s in samples)} valid; subdivisions "
                    f"{subdivisions}), {len(peer)} points; Manifold on {len(paired)} | "
                    f"{1000 * ours_wall:.1f} ms (thread CPU {1000 * ours_cpu:.1f}) | "
                    f"{1000 * theirs:.1f} ms (CPU {1000 * theirs_cpu:.1f}) | {ours_wall / theirs:.2f}x "
                    f"(CPU {ours_cpu / theirs_cpu:.2f}x) | "
                    f"{others['n']}: {others['cpu'] / max(1, others['n']):.2f} s CPU each, "
                    f"{1000 * others['cpu'] / max(1, len(samples)):.0f} ms per sample | "
                    f"{stats['evaluator_cpu_seconds']:.2f} s; run {run_wall:.1f} s wall, {run_cpu:.1f} s CPU | "
                    f"{max(vol) if vol else float('nan'):.1e} |")

        # Where a sample's time goes in the job: the subtree records (seconds
        # of each subtree root computed from its children; a cache hit costs
        # its lookup only), summed over the paired samples by op and topology.
        parts = {}
        for s in paired:
            for rec in s["subtrees"]:
                k = (rec["op"], rec["topology"][:8])
                p = parts.setdefault(k, [0.0, 0, 0])
                if rec["from_cache"]:
                    p[2] += 1
                else:
                    p[0] += rec["seconds"]
                    p[1] += 1
        geometry = sum(p[0] for p in parts.values()) / len(paired)
        top = sorted(parts.items(), key=lambda kv: -kv[1][0])[:6]
        notes.append(f"{name}: per sample {1000 * ours_wall:.1f} ms = subtrees computed {1000 * geometry:.1f} ms + "
                     f"the rest (cache lookups, properties, checks, records) {1000 * (ours_wall - geometry):.1f} ms; "
                     "largest subtrees (op, topology: ms per sample, computed / from cache): " +
                     ", ".join(f"{op} {topo}: {1000 * v[0] / len(paired):.1f} ({v[1]}/{v[2]})" for (op, topo), v in top))
        notes.append(f"{name}: per point fabatlas / Manifold ms: " +
                     " ".join(f"{1000 * s['wall']:.0f}/{1000 * peer[tuple(s['u'])][0]:.0f}" for s in paired))
        slow = sorted(paired, key=lambda s: -s["wall"])[:3]
        notes.append(f"{name}: slowest samples (u: ms, failure): " +
                     "; ".join(f"{s['u']}: {1000 * s['wall']:.0f}, {s['failure'] or 'valid'}" for s in slow))
        print(rows[-1], flush=True)
    print("\n| model | samples | fabatlas in process: mean sample wall (thread CPU), with the subtree cache | "
          "Manifold in process: mean per point of its medians, wall (process CPU) | fabatlas / Manifold | "
          "ΔG tasks: thread CPU | "
          "statistics.json evaluator CPU; `fabatlas run` process wall, CPU | max volume diff |")
    print("|---|---|---|---|---|---|---|---|")
    for row in rows:
        print(row)
    print()
    for note in notes:
        print("- " + note)
    print(f"\nload average: {os.getloadavg()}")


def coverage(timeout):
    tmp = tempfile.mkdtemp(prefix="scad-coverage-")
    counts = {"import": 0, "native": 0, "fallback": 0, "failed": 0, "no3d": 0}
    models = sorted(glob.glob(os.path.join(EXAMPLES, "*", "*.scad")))
    print("| example | import-scad | evaluation | native CSG subtrees | rendered by OpenSCAD | volume OpenSCAD / fabatlas mm^3 (diff) |")
    print("|---|---|---|---|---|---|", flush=True)
    for model in models:
        rel = os.path.relpath(model, EXAMPLES)
        imp = subprocess.run([FABATLAS, "import-scad", model, "--out", os.path.join(tmp, "imp.yaml"), "--voxel", "1"],
                             capture_output=True, text=True, timeout=timeout)
        if imp.returncode == 0:
            counts["import"] += 1
            imported = "yes"
        else:
            imported = "no: " + (imp.stderr.strip().splitlines() or ["?"])[-1].split(": ", 2)[-1][:70]
        ref = os.path.join(tmp, "ref.stl")
        if os.path.exists(ref):
            os.remove(ref)
        t, ok = openscad_stl(model, ref, timeout=timeout)
        if not ok or os.path.getsize(ref) < 100:
            counts["no3d"] += 1
            why = f"OpenSCAD's own render took over {timeout} s" if t >= timeout else "OpenSCAD renders no 3D STL (2D, echo or animation example)"
            print(f"| {rel} | {imported} | {why} | | | |", flush=True)
            continue
        size = max(bbox(ref))
        voxel = round(min(1.0, max(0.1, round(size / 150 / 0.05) * 0.05)), 2)
        design = os.path.join(tmp, "d.yaml")
        ours = os.path.join(tmp, "ours.stl")

        def evaluate(voxel):
            with open(design, "w") as f:
                f.write(f"name: coverage\nvoxel_size: {voxel}\nparameters: {{unused: {{type: real, min: 0, max: 1}}}}\n"
                        f"tree: {{op: openscad, file: {json.dumps(model)}}}\nproperties: [volume]\n")
            if os.path.exists(ours):
                os.remove(ours)
            return fabatlas_eval(design, ours, timeout=timeout)[1]

        try:
            j = evaluate(voxel)
        except subprocess.TimeoutExpired:
            counts["failed"] += 1
            print(f"| {rel} | {imported} | fabatlas took over {timeout} s | | | |", flush=True)
            continue
        except Exception as e:
            counts["failed"] += 1
            print(f"| {rel} | {imported} | fabatlas failed: {str(e)[:100]} | | | |", flush=True)
            continue
        ops = [s["op"] for s in j.get("subtrees", [])]
        native = sum(o.startswith("csg:") for o in ops)
        rendered = [o[len("csg-openscad:"):] for o in ops if o.startswith("csg-openscad:")]
        if not j.get("valid") or not os.path.exists(ours):
            counts["failed"] += 1
            print(f"| {rel} | {imported} | no geometry: {str(j.get('failure_reason', ''))[:100]} | {native} | {','.join(rendered)} | |", flush=True)
            continue
        vo, vp = volume(ref), j["properties"].get("volume", float("nan"))
        counts["fallback" if rendered else "native"] += 1
        kind = "with OpenSCAD subtrees" if rendered else "fully native"
        diff = f"{vo:.1f} / {vp:.1f} ({pct(vp, vo):+.2f}%)"
        finer = voxel
        for _ in range(3):
            if abs(pct(vp, vo)) <= 1 or finer <= 0.1:
                break
            finer = max(0.1, round(finer / 2, 3))
            try:
                vp = evaluate(finer)["properties"].get("volume", float("nan"))
            except Exception as e:
                diff += f"; at voxel {finer}: failed ({str(e)[:60]})"
                break
            diff += f"; at voxel {finer}: {vp:.1f} ({pct(vp, vo):+.2f}%)"
        counts["within1"] = counts.get("within1", 0) + (abs(pct(vp, vo)) <= 1)
        print(f"| {rel} | {imported} | {kind} at voxel {voxel} | {native} | {','.join(rendered) or '–'} | "
              f"{diff} |", flush=True)
    print(f"\n{len(models)} examples: {counts['import']} import with import-scad; of the rest of the pipeline "
          f"{counts['native']} evaluate fully natively, {counts['fallback']} with subtrees OpenSCAD renders, "
          f"{counts['failed']} fail, {counts['no3d']} have no 3D STL from OpenSCAD itself; "
          f"{counts.get('within1', 0)} within 1% of OpenSCAD's volume (at the finest voxel tried); "
          f"load average {os.getloadavg()}")


if __name__ == "__main__":
    if len(sys.argv) > 1 and sys.argv[1] == "job":
        spec = sys.argv[sys.argv.index("--samples") + 1] if "--samples" in sys.argv else "tray=40,sign=40,candleStand=24"
        budgets = {k: int(v) for k, v in (item.split("=") for item in spec.split(","))}
        job(budgets, int(sys.argv[sys.argv.index("--repeats") + 1]) if "--repeats" in sys.argv else 5,
            sys.argv[sys.argv.index("--keep") + 1] if "--keep" in sys.argv else None)
    elif len(sys.argv) > 1 and sys.argv[1] == "coverage":
        coverage(int(sys.argv[sys.argv.index("--timeout") + 1]) if "--timeout" in sys.argv else 120)
    else:
        repeats = int(sys.argv[sys.argv.index("--repeats") + 1]) if "--repeats" in sys.argv else 3
        speed(repeats, manifold="--manifold" in sys.argv)
