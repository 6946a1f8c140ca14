#!/usr/bin/env bash
# TLS as deployed (issue 20): the coordinator with certificates from
# ops/tls/make-certs.sh, and what a client meets when something is wrong:
# a certificate of another CA, a name the certificate does not carry, an
# expired and a not-yet-valid certificate, mutual TLS (--tls-client-ca)
# with and without a client certificate (the CLI and workers), and
# plaintext on a non-loopback address (refused unless
# --allow-insecure-network). Each refusal is exit status 2 with one line
# naming the reason TLS gives; each positive control runs `fabatlas jobs`.
#   tests/ops/tls_test.sh SOURCE_DIR BIN_DIR
set -euo pipefail
src=$(cd "${1:?source dir}" && pwd)
bin=$(cd "${2:?bin dir}" && pwd)
tmp=$(mktemp -d /tmp/fabatlas-tls.XXXXXX)
pids=()
cleanup() {
  for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done
  for p in "${pids[@]}"; do wait "$p" 2>/dev/null || true; done
  rm -rf "$tmp"
}
trap cleanup EXIT
fail() { echo "FAIL: $*"; exit 1; }

bash "$src/ops/tls/make-certs.sh" "$tmp/ok" localhost > /dev/null
bash "$src/ops/tls/make-certs.sh" "$tmp/other" localhost > /dev/null   # another deployment's CA
token=$(cat "$tmp/ok/token")

# A server certificate signed by the deployment CA with the given name and
# validity (openssl ca takes explicit start and end dates).
leaf() {  # name san startdate enddate
  local name=$1 san=$2 start=$3 end=$4 d=$tmp/ca-db
  mkdir -p "$d"; : > "$d/index.txt"; [[ -f $d/serial ]] || echo 1000 > "$d/serial"
  cat > "$d/ca.cnf" <<CNF
[ca]
default_ca = d
[d]
database = $d/index.txt
serial = $d/serial
new_certs_dir = $d
certificate = $tmp/ok/ca.pem
private_key = $tmp/ok/ca.key
default_md = sha256
policy = p
copy_extensions = none
unique_subject = no
[p]
commonName = supplied
[ext]
subjectAltName = $san
extendedKeyUsage = serverAuth
CNF
  openssl req -newkey rsa:2048 -nodes -subj "/CN=$name" -keyout "$tmp/$name.key" -out "$tmp/$name.csr" 2>/dev/null
  openssl ca -batch -config "$d/ca.cnf" -extensions ext -startdate "$start" -enddate "$end" \
    -in "$tmp/$name.csr" -out "$tmp/$name.pem" >/dev/null 2>&1
}
leaf expired "DNS:localhost,IP:127.0.0.1" 20200101000000Z 20210101000000Z
leaf future "DNS:localhost,IP:127.0.0.1" 20400101000000Z 20410101000000Z
leaf othername "DNS:coordinator.example.org" 20200101000000Z 20400101000000Z
leaf current "DNS:localhost,IP:127.0.0.1" 20200101000000Z 20400101000000Z   # the positive control of leaf()

n=0
coordinator() {  # name args...: starts a coordinator, sets $port
  local name=$1; shift
  rm -f "$tmp/$name.port"
  "$bin/fabatlas-coordinator" --state-dir "$tmp/state-$name" --port-file "$tmp/$name.port" --token "$token" \
    --log-level warn "$@" > "$tmp/$name.log" 2>&1 &
  pids+=($!)
  for _ in $(seq 100); do [[ -s $tmp/$name.port ]] && break; sleep 0.1; done
  [[ -s $tmp/$name.port ]] || fail "coordinator $name did not start: $(cat "$tmp/$name.log")"
  port=$(cat "$tmp/$name.port")
}
expect_ok() {  # what args...
  local what=$1; shift
  out=$(FABATLAS_TOKEN=$token "$bin/fabatlas" jobs "$@" 2>&1) || fail "$what: refused: $out"
  n=$((n + 1)); echo "ok: $what"
}
expect_refused() {  # what pattern args...: exit 2, one line, matching pattern
  local what=$1 pattern=$2; shift 2
  set +e
  out=$(FABATLAS_TOKEN=$token timeout 60 "$bin/fabatlas" jobs "$@" 2>&1)
  code=$?
  set -e
  [[ $code == 2 ]] || fail "$what: exit $code, wanted 2: $out"
  [[ $(wc -l <<<"$out") == 1 ]] || fail "$what: not one line: $out"
  grep -Eqi "$pattern" <<<"$out" || fail "$what: '$out' does not say /$pattern/"
  n=$((n + 1)); echo "refused as expected: $what: $out"
}

# The deployment as made by make-certs.sh.
coordinator good --listen 127.0.0.1:0 --tls-cert "$tmp/ok/server.pem" --tls-key "$tmp/ok/server.key"
expect_ok "TLS with the deployment CA" --coordinator "localhost:$port" --tls-ca "$tmp/ok/ca.pem"
expect_refused "another deployment's CA" "certificate verify failed" --coordinator "localhost:$port" --tls-ca "$tmp/other/ca.pem"
expect_refused "plaintext client against TLS" "cannot reach|unavailable" --coordinator "localhost:$port"
set +e; FABATLAS_TOKEN=wrong "$bin/fabatlas" jobs --coordinator "localhost:$port" --tls-ca "$tmp/ok/ca.pem" > "$tmp/wrong.out" 2>&1; code=$?; set -e
[[ $code == 2 ]] && grep -q UNAUTHENTICATED "$tmp/wrong.out" || fail "wrong token: exit $code: $(cat "$tmp/wrong.out")"

# Certificates that are wrong for the connection. The same recipe with a
# current date range and the right name is accepted, so each refusal below
# is for the one thing that differs.
coordinator current --listen 127.0.0.1:0 --tls-cert "$tmp/current.pem" --tls-key "$tmp/current.key"
expect_ok "a current certificate made by leaf()" --coordinator "localhost:$port" --tls-ca "$tmp/ok/ca.pem"
coordinator expired --listen 127.0.0.1:0 --tls-cert "$tmp/expired.pem" --tls-key "$tmp/expired.key"
expect_refused "expired server certificate" "certificate verify failed" --coordinator "localhost:$port" --tls-ca "$tmp/ok/ca.pem"
coordinator future --listen 127.0.0.1:0 --tls-cert "$tmp/future.pem" --tls-key "$tmp/future.key"
expect_refused "not-yet-valid server certificate" "certificate verify failed" --coordinator "localhost:$port" --tls-ca "$tmp/ok/ca.pem"
coordinator othername --listen 127.0.0.1:0 --tls-cert "$tmp/othername.pem" --tls-key "$tmp/othername.key"
expect_refused "certificate for another name" "peer name localhost is not in peer certificate" --coordinator "localhost:$port" --tls-ca "$tmp/ok/ca.pem"

# Mutual TLS: the coordinator requires client certificates of the CA.
coordinator mutual --listen 127.0.0.1:0 --tls-cert "$tmp/ok/server.pem" --tls-key "$tmp/ok/server.key" \
  --tls-client-ca "$tmp/ok/ca.pem"
expect_ok "mutual TLS with the client certificate" --coordinator "localhost:$port" --tls-ca "$tmp/ok/ca.pem" \
  --tls-cert "$tmp/ok/client.pem" --tls-key "$tmp/ok/client.key"
expect_refused "mutual TLS without a client certificate" "cannot reach coordinator.*(socket closed|certificate)" \
  --coordinator "localhost:$port" --tls-ca "$tmp/ok/ca.pem"
expect_refused "mutual TLS with another CA's client certificate" "cannot reach coordinator.*(socket closed|certificate)" \
  --coordinator "localhost:$port" --tls-ca "$tmp/ok/ca.pem" --tls-cert "$tmp/other/client.pem" --tls-key "$tmp/other/client.key"
# A worker with its client certificate connects and runs a job.
"$bin/fabatlas-worker" --coordinator "localhost:$port" --tls-ca "$tmp/ok/ca.pem" --tls-cert "$tmp/ok/client.pem" \
  --tls-key "$tmp/ok/client.key" --token "$token" --cache-dir "$tmp/wcache" --log-format json > "$tmp/worker.log" 2>&1 &
pids+=($!)
id=$(FABATLAS_TOKEN=$token "$bin/fabatlas" submit "$src/tests/cluster/data/tube_small.yaml" --coordinator "localhost:$port" \
  --tls-ca "$tmp/ok/ca.pem" --tls-cert "$tmp/ok/client.pem" --tls-key "$tmp/ok/client.key" | awk '{print $1}')
FABATLAS_TOKEN=$token timeout 120 "$bin/fabatlas" watch "$id" --coordinator "localhost:$port" --tls-ca "$tmp/ok/ca.pem" \
  --tls-cert "$tmp/ok/client.pem" --tls-key "$tmp/ok/client.key" > "$tmp/watch.log" 2>&1 || fail "mTLS job: $(tail -1 "$tmp/watch.log")"
grep -q '"event":"worker_connected"' "$tmp/worker.log" || fail "mTLS worker did not connect"
n=$((n + 1)); echo "ok: a worker with a client certificate ran job $id under mutual TLS"
# Workers that must not get in: no client certificate, another CA's client
# certificate (mutual TLS), and an expired server certificate. Each gives up
# after --connect-timeout with exit 2 and one line, and never connects. (A
# coordinator refusing the client certificate closes the connection; gRPC
# tells the client no more than "Socket closed".)
expect_worker_refused() {  # what pattern coordinator-port args...
  local what=$1 pattern=$2 at=$3; shift 3
  set +e
  out=$(timeout 60 "$bin/fabatlas-worker" --coordinator "localhost:$at" --tls-ca "$tmp/ok/ca.pem" --token "$token" \
    --cache-dir "$tmp/wcache-refused" --connect-timeout 3 --log-level error "$@" 2>&1)
  code=$?
  set -e
  [[ $code == 2 ]] || fail "worker $what: exit $code, wanted 2: $out"
  [[ $(wc -l <<<"$out") == 1 ]] || fail "worker $what: not one line: $out"
  grep -Eqi "cannot reach coordinator localhost:$at: .*($pattern)" <<<"$out" || fail "worker $what: '$out' does not say /$pattern/"
  grep -q worker_connected <<<"$out" && fail "worker $what connected: $out"
  n=$((n + 1)); echo "refused as expected: worker $what: $out"
}
expect_worker_refused "without a client certificate under mutual TLS" "socket closed|certificate" "$port"
expect_worker_refused "with another CA's client certificate under mutual TLS" "socket closed|certificate" "$port" \
  --tls-cert "$tmp/other/client.pem" --tls-key "$tmp/other/client.key"
mutual_port=$port
coordinator expired-w --listen 127.0.0.1:0 --tls-cert "$tmp/expired.pem" --tls-key "$tmp/expired.key"
expect_worker_refused "against an expired server certificate" "certificate verify failed" "$port"
port=$mutual_port

# Plaintext on a non-loopback address: refused, unless allowed explicitly.
set +e
out=$("$bin/fabatlas-coordinator" --listen 0.0.0.0:0 --state-dir "$tmp/state-plain" 2>&1); code=$?
set -e
[[ $code == 2 && $(wc -l <<<"$out") == 1 ]] && grep -q "refusing plaintext" <<<"$out" ||
  fail "plaintext on 0.0.0.0: exit $code: $out"
n=$((n + 1)); echo "refused as expected: plaintext on 0.0.0.0: $out"
coordinator insecure --listen 0.0.0.0:0 --allow-insecure-network
expect_ok "plaintext on 0.0.0.0 with --allow-insecure-network" --coordinator "127.0.0.1:$port"
echo "$n passed, 0 failed"
