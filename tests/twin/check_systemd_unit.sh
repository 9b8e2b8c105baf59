#!/usr/bin/env bash
# examples/peritwin@.service passes `systemd-analyze verify` with its ExecStart pointed at the
# built daemon (verify checks that the command exists): no warning, no error. A copy with an
# unknown key must be reported, so that a silent verifier cannot pass this test.
# Usage: check_systemd_unit.sh UNIT PERITWIN_BINARY
set -euo pipefail
unit=$1 daemon=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
sed "s#/usr/local/bin/peritwin#$daemon#" "$unit" >"$work/peritwin@.service"
out=$(cd "$work" && systemd-analyze verify ./peritwin@hull-aft.service 2>&1) || {
  echo "FAIL: systemd-analyze verify exited non-zero: $out"
  exit 1
}
if [ -n "$out" ]; then
  echo "FAIL: systemd-analyze verify reported: $out"
  exit 1
fi
sed 's/^RestartSec=5$/RestartSec=5\nRestartSecs=5/' "$work/peritwin@.service" >"$work/broken@.service"
bad=$(cd "$work" && systemd-analyze verify ./broken@hull-aft.service 2>&1 || true)
if ! grep -q "RestartSecs" <<<"$bad"; then
  echo "FAIL: a unit with an unknown key was not reported: $bad"
  exit 1
fi
echo "ok: $unit verified"
