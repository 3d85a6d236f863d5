#!/usr/bin/env bash
# How much of a process is the physics: the whole process's wall time against the engine
# steps' (report.json's wall_time_s, or the sum of sweep.csv's wall_s), as a ratio.
#   - the main job (scenes/yoga-mat.toml, with its MCAP), N runs;
#   - the thin tape (scenes/thin-tape.toml, with its MCAP), M runs;
#   - a 64-run sweep of the yoga mat with --jobs 1 (push speeds 0.3000-0.3063 m/s).
# Prints each one's median and range. The machine's other load changes every figure: run it
# on a quiet machine and quote the ratios, which it changes least.
# Usage: tools/overhead.sh [N] [M]   (default 15 3; needs a release build: cargo build --release)
# UNCOIL=path/to/uncoil measures another build (an earlier release, say) the same way.
set -euo pipefail
cd "$(dirname "$0")/.."
n=${1:-15}
m=${2:-3}
bin=${UNCOIL:-target/release/uncoil}
[ -x "$bin" ] || cargo build --release
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
python3 - "$bin" "$n" "$m" "$tmp" <<'PY'
import csv, json, os, statistics, subprocess, sys, time

bin, n, m, tmp = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), sys.argv[4]

def timed(cmd):
    start = time.perf_counter()
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.perf_counter() - start

def show(label, rows):
    walls = [w for w, _ in rows]
    ratios = [w / e for w, e in rows]
    engines = [e for _, e in rows]
    print(f"{label}: {len(rows)} runs; process {statistics.median(walls):.3f} s "
          f"({min(walls):.3f}-{max(walls):.3f}), engine {statistics.median(engines):.3f} s, "
          f"process / engine {statistics.median(ratios):.2f} ({min(ratios):.2f}-{max(ratios):.2f})")

for scene, runs in (("scenes/yoga-mat.toml", n), ("scenes/thin-tape.toml", m)):
    rows = []
    for _ in range(runs):
        out = os.path.join(tmp, "run")
        wall = timed([bin, "run", scene, "--out", out])
        rows.append((wall, json.load(open(os.path.join(out, "report.json")))["wall_time_s"]))
    show(scene, rows)

speeds = ",".join(f"{0.3 + 1e-4 * i:.4f}" for i in range(64))
out = os.path.join(tmp, "sweep")
wall = timed([bin, "sweep", "scenes/yoga-mat.toml", "--vary", f"push.contact_speed_m_s={speeds}",
              "--jobs", "1", "--out", out])
table = list(csv.DictReader(open(os.path.join(out, "sweep.csv"))))
engine = sum(float(r["wall_s"]) for r in table)
print(f"sweep of {len(table)} yoga mats, --jobs 1: process {wall:.2f} s, engine {engine:.2f} s, "
      f"process / engine {wall / engine:.2f}, {len(table) / wall:.1f} runs/s")
PY
