#!/bin/bash
# Peak RSS of the coordinator over one job (docs/benchmarks.md, "Artifact"; docs/benchmarks-history.md, "Streaming
# the artifact's cache entries"): fabatlas-coordinator under GNU time, two
# workers, `fabatlas submit` + `fabatlas watch`, then SIGTERM.
# usage: bench/artifact/coordinator_rss.sh BIN_DIR OUT_DIR JOB_YAML
# Prints OUT_DIR/coordinator.time (GNU time -v) and the job's cache events.
set -eu
BIN=$1; OUT=$2; JOB=$3
rm -rf "$OUT"; mkdir -p "$OUT"
/usr/bin/time -v -o "$OUT/coordinator.time" "$BIN/fabatlas-coordinator" --listen 127.0.0.1:0 \
  --state-dir "$OUT/state" --port-file "$OUT/port" > "$OUT/coordinator.log" 2>&1 &
TIME_PID=$!
for _ in $(seq 100); do [ -s "$OUT/port" ] && break; sleep 0.2; done
PORT=$(cat "$OUT/port")
"$BIN/fabatlas-worker" --coordinator "127.0.0.1:$PORT" --cache-dir "$OUT/w0" > "$OUT/w0.log" 2>&1 &
W0=$!
"$BIN/fabatlas-worker" --coordinator "127.0.0.1:$PORT" --cache-dir "$OUT/w1" > "$OUT/w1.log" 2>&1 &
W1=$!
ID=$("$BIN/fabatlas" submit "$JOB" --coordinator "127.0.0.1:$PORT" | cut -d' ' -f1)
"$BIN/fabatlas" watch "$ID" --coordinator "127.0.0.1:$PORT" > "$OUT/watch.log" 2>&1 || true
kill -TERM "$W0" "$W1"; wait "$W0" "$W1" || true
kill -TERM "$(pgrep -P "$TIME_PID")"; wait "$TIME_PID" || true
grep -E "Maximum resident|User time|System time|Elapsed" "$OUT/coordinator.time"
sqlite3 "$OUT/state/state.db" "SELECT kind, message FROM events WHERE kind IN ('cache_plan', 'cache')"
ls -l "$OUT"/state/jobs/*/out/*.fabatlas
