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
# The baseline, in the same minutes: where `cyclictest` is installed (Debian `rt-tests`), before each run it
# measures the host's wake-up latency for 6 s at the device loop's period and real-time priority, nothing of
# ours running, and prints the share of wake-ups late enough to be a device-loop miss (later than the period
# plus the loop's spin margin, haptics::haptic_loop::SPIN_MARGIN, less a 10 us step): the floor the host sets
# under the loop's own "late starts" (the server's report splits its misses by cause). Both hold the CPUs' wake-up
# latency at 0 (PM QoS), or neither (SERVE_ARGS="--no-cpu-latency-hold").
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=${COIFFURE_BIN:-target/release/coiffure}
if [ $# -gt 0 ]; then RATES=("$@"); else RATES=(4000 10000); fi
mkdir -p bench/out
web=$(mktemp -d)
echo '<!doctype html><title>bench</title>' > "$web/index.html"
host_floor() {
    # Priority 10: the server's default --haptic-priority, the device loop's.
    local rate=$1 period=$((1000000 / $1)) out
    command -v cyclictest > /dev/null || { echo "== host: cyclictest not installed (apt-get install rt-tests): no baseline"; return; }
    # cyclictest holds the CPUs' wake-up latency at 0 as the server does (PM QoS), unless the server is told not to.
    local qos=()
    [[ "${SERVE_ARGS:-}" == *--no-cpu-latency-hold* ]] && qos=(--laptop)
    out=$(cyclictest -m -p 10 -i "$period" -t 1 -D 6 -q -h 2000 "${qos[@]}" 2>&1) || { echo "== host: cyclictest failed: $out" | head -3; return; }
    echo "$out" | awk -v lim=$((period + 60 - 10)) -v rate="$rate" '
        /^#/ { if ($0 ~ /Overflows/) over = $NF + 0; if ($0 ~ /Max Latencies/) max = $NF + 0; next }
        { n += $2; if ($1 + 0 > lim) late += $2; h[$1 + 0] = $2 }
        END { n += over; late += over; acc = 0; p = -1
              for (i = 0; i < 2000; i++) { acc += h[i]; if (p < 0 && acc >= 0.999 * n) p = i }
              printf "== host (cyclictest at %d Hz, nothing of ours running): %d wake-ups, later than %d us (a miss): %d (%.3f %%), p99.9 %s us, max %d us\n", rate, n, lim, late, 100 * late / n, (p < 0 ? ">2000" : p), max }'
}
for rate in "${RATES[@]}"; do
    host_floor "$rate"
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
    grep -o "haptic loop:.*CPU wake-up latency held at 0: [a-z]*" "$log"
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
