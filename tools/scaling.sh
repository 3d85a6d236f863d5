#!/usr/bin/env bash
# Wall time per simulated second and per step against the number of links, at a fixed
# time step: the thin tape's first simulated second (dt = max_dt_s, the coil turning
# slowly), with 7, 33 and 333 links per turn (about 2k, 10k and 100k links).
# Usage: tools/scaling.sh [links_per_turn ...]   (needs a release build: cargo build --release)
set -euo pipefail
cd "$(dirname "$0")/.."
bin=target/release/uncoil
[ -x "$bin" ] || cargo build --release
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
printf '%-15s %8s %8s %12s %12s\n' links_per_turn links steps wall_s_per_s us_per_step
for n in "${@:-7 33 333}"; do
  for k in $n; do
    sed -e "s/^links_per_turn = .*/links_per_turn = $k/" \
        -e "s/^max_time_s = .*/max_time_s = 1.0/" scenes/thin-tape.toml > "$tmp/s.toml"
    "$bin" run "$tmp/s.toml" --out "$tmp/out" > /dev/null 2>&1
    python3 - "$tmp/out/report.json" "$k" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
print(f"{sys.argv[2]:<15} {r['links']:>8} {r['steps']:>8} {r['wall_time_s']/r['sim_time_s']:>12.4f} {1e6*r['wall_time_s']/r['steps']:>12.2f}")
PY
  done
done
