#!/usr/bin/env bash
# What writing run.mcap costs: runs a scene alternately with and without the MCAP log
# (--no-mcap), N times each, and prints the median process wall time and CPU time (user +
# sys, from wait4) of each with their range, their ratio, the share of the process's wall
# time spent outside the engine steps (1 - report.json's wall_time_s / the process's), and
# the size of run.mcap. Alternating pairs keep a shared machine's drift out of the ratio;
# the ratio is also given as the median of the pairs' own ratios.
# Usage: tools/mcap_cost.sh [scene] [N]   (default: scenes/yoga-mat.toml 15; needs a release
# build: cargo build --release)
set -euo pipefail
cd "$(dirname "$0")/.."
scene=${1:-scenes/yoga-mat.toml}
n=${2:-15}
bin=target/release/uncoil
[ -x "$bin" ] || cargo build --release
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
python3 - "$bin" "$scene" "$n" "$tmp" <<'PY'
import json, os, statistics, subprocess, sys, time

bin, scene, n, tmp = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4]
modes = ("no-mcap", "mcap")
rows = {m: [] for m in modes}
for _ in range(n):
    for mode in modes:
        out = os.path.join(tmp, mode)
        cmd = [bin, "run", scene, "--out", out] + (["--no-mcap"] if mode == "no-mcap" else [])
        start = time.perf_counter()
        p = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        _, status, usage = os.wait4(p.pid, 0)
        wall = time.perf_counter() - start
        if os.waitstatus_to_exitcode(status) != 0:
            sys.exit(f"{' '.join(cmd)} failed")
        engine = json.load(open(os.path.join(out, "report.json")))["wall_time_s"]
        rows[mode].append((wall, usage.ru_utime + usage.ru_stime, 1 - engine / wall))

def med(mode, k):
    return statistics.median(r[k] for r in rows[mode])

print(f"{scene}: {n} runs each, alternating")
for m in modes:
    walls = [r[0] for r in rows[m]]
    cpus = [r[1] for r in rows[m]]
    print(f"{m:>8}: wall median {1e3 * med(m, 0):.1f} ms ({1e3 * min(walls):.1f}-{1e3 * max(walls):.1f}), "
          f"cpu median {1e3 * med(m, 1):.1f} ms ({1e3 * min(cpus):.1f}-{1e3 * max(cpus):.1f}), "
          f"outside the engine steps {100 * med(m, 2):.0f} %")
pairs = [b[0] / a[0] - 1 for a, b in zip(rows["no-mcap"], rows["mcap"])]
print(f"MCAP cost: wall {100 * (med('mcap', 0) / med('no-mcap', 0) - 1):+.1f} % of medians, "
      f"{100 * statistics.median(pairs):+.1f} % median of pairs; "
      f"cpu {100 * (med('mcap', 1) / med('no-mcap', 1) - 1):+.1f} %")
print(f"run.mcap: {os.path.getsize(os.path.join(tmp, 'mcap', 'run.mcap')) / 1e6:.3f} MB")
PY
