#!/usr/bin/env bash
# The demo: installs the Debian packages, builds, then runs the twin service end to end on the
# B1 compact-tension example (examples/b1-ct-al6061.toml, the 1 mm demo grid):
#   an LCM TCP hub on 127.0.0.1 (lcm.jar's TCPService; nothing leaves the machine),
#   the daemon (build/bin/peritwin --deterministic),
#   the replay tool in lockstep feeding examples/b1-cycles.csv (64 x 1000 cycles at 4 kN, R 0.1)
#   and, at their cycles, the inspections of examples/b1-inspections.csv (the twin's ensemble
#   learns from them: the end of life's percentiles narrow; docs/prognostics.md),
# and prints every state (the web dashboard peritwin-dashboard shows them too, its URL printed): cycles, broken bonds, crack length and the remaining life with its band
# (re-estimated every 10 batches). Authenticated: the script generates a key file
# (out/demo/keys.toml, mode 0600, keys "replay", "stream" and "peritwin"), the daemon's config is the example
# plus an [auth] table naming it, and the replay signs its batches and verifies every state. The daemon stops at the end-of-life criterion (8 mm of crack
# growth), then gets SIGTERM, checkpoints and writes its results and pictures under out/demo/.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$(pwd)
bash scripts/install-deps.sh
build=${BUILD_DIR:-build}
cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$build" -j "$(nproc)" --target peritwin peritwin-replay peritwin-dashboard
bin="$root/$build/bin"

demo="$root/out/demo"
rm -rf "$demo"
mkdir -p "$demo"

# A free loopback port for the hub (PORT=... to choose one).
port=${PORT:-}
if [ -z "$port" ]; then
  for p in $(seq 7731 7799); do
    if ! (exec 3<>"/dev/tcp/127.0.0.1/$p") 2>/dev/null; then port=$p; break; fi
  done
fi
url="tcpq://127.0.0.1:$port"

hub_pid="" daemon_pid="" dashboard_pid=""
cleanup() {
  if [ -n "$dashboard_pid" ] && kill -0 "$dashboard_pid" 2>/dev/null; then kill -TERM "$dashboard_pid"; fi
  if [ -n "$daemon_pid" ] && kill -0 "$daemon_pid" 2>/dev/null; then kill -TERM "$daemon_pid"; fi
  if [ -n "$hub_pid" ] && kill -0 "$hub_pid" 2>/dev/null; then kill "$hub_pid"; fi
}
trap cleanup EXIT

start=$(date +%s)
java -cp /usr/share/java/lcm.jar lcm.lcm.TCPService "$port" >"$demo/hub.log" 2>&1 &
hub_pid=$!
for _ in $(seq 100); do
  (exec 3<>"/dev/tcp/127.0.0.1/$port") 2>/dev/null && break
  sleep 0.1
done
echo "demo: LCM hub on $url (log: out/demo/hub.log)"

# The web dashboard (read-only) on a free loopback port; it prints its URL first.
"$bin/peritwin-dashboard" --lcm-url "$url" --listen 127.0.0.1:0 >"$demo/dashboard.url" \
  2>"$demo/dashboard.log" &
dashboard_pid=$!
for _ in $(seq 100); do
  [ -s "$demo/dashboard.url" ] && break
  sleep 0.1
done
dashboard_url=$(grep -o 'http://[^ ]*' "$demo/dashboard.url" || true)
echo "demo: dashboard on $dashboard_url (log: out/demo/dashboard.log)"

# Keys: one per producer ("replay"; "stream" for peritwin-stream, README "Streaming from
# sensors") and the daemon's own ("peritwin"), HMAC-SHA256.
"$bin/peritwin-replay" --generate-key-file "$demo/keys.toml" --key-ids replay,stream,peritwin
{ cat "$root/examples/b1-ct-al6061.toml"; printf '\n[auth]\nkey_file = "keys.toml"\n'; } \
  >"$demo/b1-ct.toml"

(cd "$demo" && exec "$bin/peritwin" --config "$demo/b1-ct.toml" \
   --lcm-url "$url" --state-dir state --deterministic) >"$demo/daemon.log" 2>&1 &
daemon_pid=$!
echo "demo: daemon started (log: out/demo/daemon.log); replaying examples/b1-cycles.csv in lockstep"
echo "      with the inspections of examples/b1-inspections.csv at 8 000, 20 000 and 28 000 cycles"
echo

"$bin/peritwin-replay" --config examples/b1-ct-al6061.toml --key-file "$demo/keys.toml" \
  --history examples/b1-cycles.csv --format cycles --lcm-url "$url" --lockstep \
  --observations examples/b1-inspections.csv 2> >(grep -v '^LCM tcpq' >&2)

echo
# DASHBOARD_SCREENSHOT=file.png: headless chromium's picture of the dashboard at the end.
if [ -n "${DASHBOARD_SCREENSHOT:-}" ] && command -v chromium >/dev/null; then
  chromium --headless --no-sandbox --disable-gpu --window-size=1300,1000 \
    --virtual-time-budget=10000 --screenshot="$DASHBOARD_SCREENSHOT" "${dashboard_url}?events=off" \
    >/dev/null 2>&1 && echo "demo: dashboard screenshot in $DASHBOARD_SCREENSHOT"
fi
kill -TERM "$dashboard_pid"
wait "$dashboard_pid" || true
dashboard_pid=""
kill -TERM "$daemon_pid"
rc=0
wait "$daemon_pid" || rc=$?
daemon_pid=""
echo "demo: daemon stopped with exit code $rc after $(( $(date +%s) - start )) s"
grep -E "checkpoint \(stop\)|pictures|stopped at" "$demo/daemon.log" | sed 's/^[^ ]* [^ ]* [a-z]* /  /'
echo
echo "demo: results in out/demo/results/b1-ct/"
echo "  b1-ct.h5 + b1-ct.xdmf    time series and damage snapshots (open the .xdmf in ParaView)"
echo "  b1-ct-damage.png         damage map at the end"
echo "  b1-ct-crack-length.png   crack length against cycles"
echo "  checkpoints in out/demo/state/b1-ct/ (a restart of the daemon resumes from them)"
exit "$rc"
