#!/bin/bash
# Peak resident memory of `fabatlas serve` (docs/benchmarks.md "Artifact"):
# starts BIN serve ART on a free port under /usr/bin/time -v, asks 200
# /api/intervals at uniform random points of the form's space and 3
# /api/preview.glb, waits SETTLE seconds (default 30: the background preview
# warm-up), stops it with SIGINT and prints its lines and maximum RSS.
#   bench/artifact/serve_rss.sh build/bin/fabatlas ART [serve args, e.g. --preview-cache-mb 0]
set -e
BIN=$1; ART=$2; shift 2
OUT=$(mktemp -d /tmp/serve-rss-XXXX)
nice -n 15 /usr/bin/time -v "$BIN" serve "$ART" --port 0 "$@" > "$OUT/out" 2> "$OUT/err" &
TPID=$!
for _ in $(seq 120); do grep -q 127.0.0.1 "$OUT/out" 2>/dev/null && break; sleep 1; done
PORT=$(grep -o '127.0.0.1:[0-9]*' "$OUT/out" | cut -d: -f2)
python3 - "$PORT" <<'PY'
import json, random, sys, urllib.request
base = f"http://127.0.0.1:{sys.argv[1]}"
dims = json.load(urllib.request.urlopen(base + "/api/form"))["dimensions"]
random.seed(1)
point = lambda: ",".join(f"{random.uniform(d['lo'], d['hi']):.6g}" for d in dims)
for _ in range(200): urllib.request.urlopen(f"{base}/api/intervals?u={point()}").read()
for _ in range(3): urllib.request.urlopen(f"{base}/api/preview.glb?u={point()}").read()
print("200 intervals, 3 previews")
PY
sleep "${SETTLE:-30}"
kill -INT "$(pgrep -P $TPID -x fabatlas)"
wait $TPID || true
cat "$OUT/out"; grep "Maximum resident" "$OUT/err"
rm -rf "$OUT"
