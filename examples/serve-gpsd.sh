#!/usr/bin/env bash
# skytrace as a live GNSS receiver for gpsd: `skytrace serve` streams the quick-start receiver's
# NMEA over TCP in real time, gpsd reads it like a receiver on a network port, and gpspipe prints
# gpsd's reports (TPV with mode 3 and the fix, SKY with the satellites). Any gpsd client (cgps,
# xgps, a robot's gpsd driver) can connect to gpsd's port instead.
# Usage: examples/serve-gpsd.sh [REPORTS]   (default 10 gpsd reports, then everything stops)
set -euo pipefail
cd "$(dirname "$0")/.."
reports="${1:-10}"
skytrace="${SKYTRACE:-build/bin/skytrace}"
work=$(mktemp -d)
pids=()
trap 'kill "${pids[@]}" 2>/dev/null || true; wait 2>/dev/null || true; rm -rf "$work"' EXIT

# Port 0: the system picks a free port, which skytrace serve prints. The log exists before the
# background process opens it, so that the first look for the port never finds no file.
: >"$work/serve.log"
"$skytrace" serve examples/quickstart.yaml --nmea-tcp 127.0.0.1:0 --rate-hz 1 >"$work/serve.log" 2>&1 &
pids+=($!)
for _ in $(seq 100); do
  port=$(sed -n 's/.*skytrace serve: NMEA on tcp port \([0-9]*\).*/\1/p' "$work/serve.log")
  [[ -n "$port" ]] && break
  sleep 0.1
done
[[ -n "${port:-}" ]] || { cat "$work/serve.log" >&2; exit 1; }
echo "skytrace serve: NMEA on 127.0.0.1:$port" >&2

# gpsd in the foreground (-N), reading at once (-n), its clients' port chosen away from 2947 so that
# a system gpsd does not get in the way.
gpsd_port=$((20000 + $$ % 20000))
/usr/sbin/gpsd -N -n -S "$gpsd_port" "tcp://127.0.0.1:$port" >"$work/gpsd.log" 2>&1 &
pids+=($!)
sleep 1
echo "gpsd: clients on 127.0.0.1:$gpsd_port" >&2
timeout 60 gpspipe -w -n "$reports" "127.0.0.1:$gpsd_port"
