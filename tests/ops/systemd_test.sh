#!/usr/bin/env bash
# The systemd units of ops/systemd (issue 16): `systemd-analyze verify` finds
# nothing wrong and `systemd-analyze security` rates each unit's exposure at
# most 4.0 ("OK" or "MEDIUM"). ExecStart is pointed at the built binaries,
# since verify checks that the program exists.
#   tests/ops/systemd_test.sh SOURCE_DIR BIN_DIR
set -euo pipefail
src=$(cd "${1:?source dir}" && pwd)
bin=$(cd "${2:?bin dir}" && pwd)
command -v systemd-analyze >/dev/null || { echo "SKIP: systemd-analyze missing"; exit 77; }
tmp=$(mktemp -d /tmp/fabatlas-systemd.XXXXXX)
trap 'rm -rf "$tmp"' EXIT
status=0
for unit in "$src"/ops/systemd/*.service; do
  name=$(basename "$unit")
  sed "s#/usr/local/bin/#$bin/#" "$unit" > "$tmp/$name"
  if ! out=$(cd "$tmp" && systemd-analyze verify "./$name" 2>&1) || [[ -n $out ]]; then
    echo "$name: systemd-analyze verify: $out"; status=1
  fi
  line=$(cd "$tmp" && systemd-analyze security --offline=true "./$name" 2>&1 | grep 'Overall exposure level')
  score=$(sed -E 's/.*: ([0-9.]+) .*/\1/' <<<"$line")
  if ! awk -v s="$score" 'BEGIN { exit !(s != "" && s <= 4.0) }'; then
    echo "$name: exposure $score above 4.0 ($line)"; status=1
  fi
  echo "$name: verify clean, exposure $score"
  # The hardening an operator relies on is in the unit itself.
  for key in DynamicUser=yes LoadCredential=token: ProtectSystem=strict RestartPreventExitStatus=2; do
    grep -q "^$key" "$unit" || { echo "$name: lacks $key"; status=1; }
  done
done
grep -q '^StateDirectory=fabatlas' "$src/ops/systemd/fabatlas-coordinator.service" || { echo "coordinator: no StateDirectory="; status=1; }
# Exit status 75 (an I/O error at start) is restarted, however long it lasts.
grep -q '^StartLimitIntervalSec=0' "$src/ops/systemd/fabatlas-coordinator.service" || { echo "coordinator: a start limit"; status=1; }
if grep -q '^RestartPreventExitStatus=.*75' "$src/ops/systemd/fabatlas-coordinator.service"; then echo "coordinator: 75 not restarted"; status=1; fi
if grep -q '^LoadCredential=server' "$src/ops/systemd/fabatlas-worker@.service"; then echo "worker unit loads the server key"; status=1; fi
exit $status
