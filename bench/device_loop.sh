#!/usr/bin/env bash
# The live loop driven by a haptic device (issues 13, 31): `coiffure serve --device` on the built-in head (100k
# render strands), the physics at 1 kHz and the device loop at 4 and 10 kHz (`--device-rate`), with
# `coiffure device-sim` streaming the comb strokes of bench/device-comb.toml (in the back hair from 0.3 s to
# 5.55 s) at 1 kHz. Prints, per device rate, the server's haptic line (the physics: step p50, p99, p99.9, its CPU
# time's mean and p99.9 and the steps preempted (wall over CPU time by 0.1 periods), steps
# over the period; the device loop: step p99.9, misses), its strand budget line, and device-sim's round trip
# distribution, and keeps the device-sim traces in bench/out/ (their force quality: python3
# bench/device_forces.py bench/out/device-4000.csv). Run after `cargo build --release -p coiffure-server`.
#   bench/device_loop.sh [DEVICE_RATES...]        e.g. bench/device_loop.sh 4000 10000 (the default)
#   COIFFURE_BIN=path/to/coiffure SERVE_ARGS="--haptic-priority 0" SIM_ARGS="--loss 0.01" bench/device_loop.sh
#   RECORD=1 bench/device_loop.sh    also records each session and prints the force quality at the device rate
#                                    (the record replayed: bench/out/replay-RATE/device_force.csv)
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=${COIFFURE_BIN:-target/release/coiffure}
if [ $# -gt 0 ]; then RATES=("$@"); else RATES=(4000 10000); fi
mkdir -p bench/out
web=$(mktemp -d)
echo '<!doctype html><title>bench</title>' > "$web/index.html"
for rate in "${RATES[@]}"; do
    log=$(mktemp)
    rec=()
    [ -n "${RECORD:-}" ] && rec=(--record "bench/out/device-$rate.rec")
    "$BIN" serve --port 0 --web "$web" --device udp:127.0.0.1:0 --device-rate "$rate" --duration 6.5 "${rec[@]}" ${SERVE_ARGS:-} > "$log" 2>/dev/null &
    pid=$!
    # The device is bound before the scene is built; the session (and --duration) starts when the server
    # listens: stream from then, or the first poses wait in the socket while the scene builds.
    for _ in $(seq 600); do grep -q "listening on" "$log" && break; sleep 0.2; done
    addr=$(sed -n 's/.*device on udp:\([^ ]*\).*/\1/p' "$log")
    [ -n "$addr" ] || { echo "serve did not start:"; cat "$log"; kill "$pid"; exit 1; }
    sim=$("$BIN" device-sim --server "udp:$addr" --path bench/device-comb.toml --rate 1000 --duration 6.2 --out "bench/out/device-$rate.csv" ${SIM_ARGS:-})
    wait "$pid"
    echo "== device loop $rate Hz (physics 1000 Hz); load $(cut -d' ' -f1-3 /proc/loadavg)"
    grep -o "haptic loop:.*real-time priority: [a-z]*" "$log"
    grep "^strand budget:" "$log" || true
    grep "^device:" "$log"
    echo "$sim"
    if [ -n "${RECORD:-}" ]; then
        # The server's force at the device loop's rate, replayed from its record (bit for bit what it sent).
        "$BIN" replay "bench/out/device-$rate.rec" --out "bench/out/replay-$rate" > /dev/null
        python3 bench/device_forces.py "bench/out/replay-$rate/device_force.csv"
    fi
    rm -f "$log"
done
rm -rf "$web"
