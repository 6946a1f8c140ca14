#!/usr/bin/env python3
"""What a preview at the sliders' exact point costs (docs/viewer.md, Exact
previews): a real `fabatlas serve ART --exact-budget-ms 600000` (every exact
preview evaluated), once its preview cache is warm, asked for N random points
of the valid region in turn with exact=0 (the snapped sample's, its peer) and
exact=1. Prints p50 / p99 of the round trips and of the server's exact time
(X-Preview-Seconds), how far the estimate (X-Preview-Estimate, made before
each evaluation) was from the time measured, and the share of points the
default budget of 150 ms would have shown exactly.

  bench/viewer/exact_preview.py ART [N] [SEED]
  e.g. bench/viewer/exact_preview.py build/test-fixtures/viewer-pawn 200 1
"""
import json
import os
import random
import re
import statistics
import subprocess
import sys
import time
import urllib.request

art = sys.argv[1]
n = int(sys.argv[2]) if len(sys.argv) > 2 else 200
rng = random.Random(int(sys.argv[3]) if len(sys.argv) > 3 else 1)
binary = os.path.join(os.environ.get("FABATLAS_BIN_DIR", "build/bin"), "fabatlas")
serve = subprocess.Popen([binary, "serve", art, "--port", "0", "--exact-budget-ms", "600000"],
                         stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
try:
    url = None
    for line in serve.stdout:
        m = re.search(r"at (http://127\.0\.0\.1:\d+/)", line)
        if m:
            url = m.group(1)
        if "preview cache warm" in line or "warming the preview cache stopped" in line:
            break
    assert url, "fabatlas serve did not start"

    def get(path):
        start = time.perf_counter()
        with urllib.request.urlopen(url + path) as r:
            body = r.read()
            return time.perf_counter() - start, r.headers, body

    form = json.loads(get("api/form")[2])
    dims = form["dimensions"]

    def random_point():
        u = []
        for d in dims:
            v = rng.uniform(d["lo"], d["hi"])
            u.append(v if d["kind"] == "real" else round(v))
        return ",".join(repr(v) for v in u)

    snapped, exact, server, error, within = [], [], [], [], 0
    while len(exact) < n:
        u = random_point()
        if not json.loads(get("api/intervals?u=" + u)[2])["valid"]:
            continue
        snapped.append(get("api/preview.glb?u=" + u)[0])
        wall, headers, _ = get("api/preview.glb?exact=1&u=" + u)
        if headers["X-Preview"] != "exact":
            print("snapped at", u, headers.get("X-Preview-Fallback"))
            continue
        exact.append(wall)
        seconds, estimate = float(headers["X-Preview-Seconds"]), float(headers["X-Preview-Estimate"])
        server.append(seconds)
        error.append(abs(estimate - seconds) / seconds)
        within += estimate <= 0.150

    def p(xs, q):
        xs = sorted(xs)
        return xs[min(len(xs) - 1, int(q * len(xs)))] * 1000

    print(f"{form['name']}: {n} valid random points, cache {form['cache']}")
    print(f"snapped round trip p50 / p99 {p(snapped, .5):.1f} / {p(snapped, .99):.1f} ms")
    print(f"exact round trip   p50 / p99 {p(exact, .5):.1f} / {p(exact, .99):.1f} ms")
    print(f"exact server time  p50 / p99 {p(server, .5):.1f} / {p(server, .99):.1f} ms")
    print(f"estimate error p50 {statistics.median(error) * 100:.0f}%; within the default 150 ms: {within}/{n}")
    print(f"load {os.getloadavg()[0]:.1f}")
finally:
    serve.terminate()
    serve.wait()
