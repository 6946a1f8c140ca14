#!/usr/bin/env bash
# Makes a per-deployment CA and certificates for the fabatlas cluster.
#   ops/tls/make-certs.sh OUT_DIR [COORDINATOR_HOST ...]
# Writes OUT_DIR/ca.pem (give it to workers and operators: --tls-ca),
# OUT_DIR/ca.key (keep it offline), OUT_DIR/server.pem + server.key (the
# coordinator: --tls-cert/--tls-key; subjectAltName = the hosts given, plus
# localhost and 127.0.0.1), and OUT_DIR/client.pem + client.key (optional
# client certificates: coordinator --tls-client-ca ca.pem, workers
# --tls-cert/--tls-key). Also a random bearer token in OUT_DIR/token.
set -euo pipefail
out=${1:?usage: make-certs.sh OUT_DIR [COORDINATOR_HOST ...]}
shift || true
mkdir -p "$out"
umask 077
san="DNS:localhost,IP:127.0.0.1"
for h in "$@"; do
  if [[ $h =~ ^[0-9.]+$ ]]; then san="$san,IP:$h"; else san="$san,DNS:$h"; fi
done
days=825
openssl req -x509 -newkey rsa:3072 -nodes -sha256 -days 3650 -subj "/CN=fabatlas deployment CA" \
  -keyout "$out/ca.key" -out "$out/ca.pem" 2>/dev/null
make_leaf() {  # name cn extensions
  local name=$1 cn=$2 ext=$3
  openssl req -newkey rsa:2048 -nodes -sha256 -subj "/CN=$cn" \
    -keyout "$out/$name.key" -out "$out/$name.csr" 2>/dev/null
  printf '%s\n' "$ext" > "$out/$name.ext"
  openssl x509 -req -in "$out/$name.csr" -CA "$out/ca.pem" -CAkey "$out/ca.key" -CAcreateserial \
    -days $days -sha256 -extfile "$out/$name.ext" -out "$out/$name.pem" 2>/dev/null
  rm -f "$out/$name.csr" "$out/$name.ext"
}
make_leaf server "${1:-localhost}" "subjectAltName=$san
extendedKeyUsage=serverAuth"
make_leaf client "fabatlas-worker" "extendedKeyUsage=clientAuth"
openssl rand -hex 24 > "$out/token"
chmod 644 "$out/ca.pem" "$out/server.pem" "$out/client.pem"
echo "wrote $out/{ca,server,client}.{pem,key} and $out/token"
