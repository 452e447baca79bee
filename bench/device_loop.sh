#!/usr/bin/env bash
# The live loop driven by a haptic device (issue 13): `coiffure serve --device` on the built-in head (100k
# render strands) at haptic rates of 1, 2 and 4 kHz, with `coiffure device-sim` streaming the comb strokes of
# bench/device-comb.toml (in the back hair from 0.3 s to 5.55 s) at 1 kHz. Prints, per rate, the server's
# haptic loop line (step p50, p99, p99.9, misses), its strand budget line, and device-sim's round trip distribution, and keeps the
# device-sim traces in bench/out/ (their force quality: python3 bench/device_forces.py bench/out/device-1000.csv). Run on a quiet machine, after `cargo build --release -p coiffure-server`.
#   bench/device_loop.sh [RATES...]        e.g. bench/device_loop.sh 1000 4000
#   COIFFURE_BIN=path/to/coiffure SERVE_ARGS="--haptic-priority 0" bench/device_loop.sh
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=${COIFFURE_BIN:-target/release/coiffure}
if [ $# -gt 0 ]; then RATES=("$@"); else RATES=(1000 2000 4000); fi
mkdir -p bench/out
web=$(mktemp -d)
echo '<!doctype html><title>bench</title>' > "$web/index.html"
for rate in "${RATES[@]}"; do
    log=$(mktemp)
    "$BIN" serve --port 0 --web "$web" --device udp:127.0.0.1:0 --haptic-rate "$rate" --duration 6.5 ${SERVE_ARGS:-} > "$log" 2>/dev/null &
    pid=$!
    for _ in $(seq 600); do grep -q "device on udp:" "$log" && break; sleep 0.2; done
    addr=$(sed -n 's/.*device on udp:\([^ ]*\).*/\1/p' "$log")
    [ -n "$addr" ] || { echo "serve did not start:"; cat "$log"; kill "$pid"; exit 1; }
    sim=$("$BIN" device-sim --server "udp:$addr" --path bench/device-comb.toml --rate 1000 --duration 6.2 --out "bench/out/device-$rate.csv")
    wait "$pid"
    echo "== haptic rate $rate Hz"
    grep -o "haptic loop:.*real-time priority: [a-z]*" "$log"
    grep "^strand budget:" "$log" || true
    grep "^device:" "$log"
    echo "$sim"
    rm -f "$log"
done
rm -rf "$web"
