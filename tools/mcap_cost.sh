#!/usr/bin/env bash
# What writing run.mcap costs: runs a scene alternately with and without the MCAP log
# (--no-mcap), N times each, and prints the median process wall time and CPU time (user +
# sys) of each, their ratio, the share of the process's wall time spent outside the engine
# steps (1 - report.json's wall_time_s / the process's), and the size of run.mcap.
# Usage: tools/mcap_cost.sh [scene] [N]   (default: scenes/yoga-mat.toml 7; needs a release
# build: cargo build --release)
set -euo pipefail
cd "$(dirname "$0")/.."
scene=${1:-scenes/yoga-mat.toml}
n=${2:-7}
bin=target/release/uncoil
[ -x "$bin" ] || cargo build --release
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
for i in $(seq "$n"); do
  for mode in mcap no-mcap; do
    flag=()
    [ "$mode" = no-mcap ] && flag=(--no-mcap)
    /usr/bin/time -f "$mode %e %U %S" -o "$tmp/one" \
      "$bin" run "$scene" --out "$tmp/$mode" "${flag[@]}" > /dev/null 2>&1
    engine=$(python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["wall_time_s"])' "$tmp/$mode/report.json")
    echo "$(cat "$tmp/one") $engine" >> "$tmp/times"
  done
done
python3 - "$tmp/times" "$tmp/mcap/run.mcap" "$n" <<'PY'
import os, statistics, sys
rows = [l.split() for l in open(sys.argv[1]) if l.strip()]
def med(mode, f):
    return statistics.median(f(r) for r in rows if r[0] == mode)
wall = {m: med(m, lambda r: float(r[1])) for m in ("mcap", "no-mcap")}
cpu = {m: med(m, lambda r: float(r[2]) + float(r[3])) for m in ("mcap", "no-mcap")}
spread = {m: (min(float(r[1]) for r in rows if r[0] == m), max(float(r[1]) for r in rows if r[0] == m)) for m in wall}
print(f"runs: {sys.argv[3]} each, alternating")
for m in ("no-mcap", "mcap"):
    print(f"{m:>8}: wall median {wall[m]:.3f} s (min {spread[m][0]:.3f}, max {spread[m][1]:.3f}), cpu median {cpu[m]:.3f} s")
for m in ("no-mcap", "mcap"):
    share = sorted(1 - float(r[4]) / float(r[1]) for r in rows if r[0] == m)
    print(f"{m:>8}: outside the engine steps, median {100 * statistics.median(share):.0f} % of the process (min {100 * share[0]:.0f}, max {100 * share[-1]:.0f})")
print(f"MCAP cost: wall {100 * (wall['mcap'] / wall['no-mcap'] - 1):+.1f} %, cpu {100 * (cpu['mcap'] / cpu['no-mcap'] - 1):+.1f} %")
print(f"run.mcap: {os.path.getsize(sys.argv[2]) / 1e6:.2f} MB")
PY
