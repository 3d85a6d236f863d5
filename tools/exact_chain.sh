#!/usr/bin/env bash
# The exact chain's figures of docs/final-bang.md and docs/folded-chain.md, each an ensemble
# (mean and standard error of the mean) or a table read from the runs' report.json:
#   folded-free   the folded chain without a floor at 50, 200, 500 and 2000 links
#   folded-table  onto a table, 8 pin heights 0.70-0.84 L, at 50 and 200 links, two steps
#   coil NAME...  a shipped scene's 8 pushes on each bang engine (default: yoga-mat; the
#                 thin tape's take about 15 minutes)
#   thin-converge the thin tape's 8 pushes on the exact chain with pieces of b, 2 b and 5 b
#                 at its 0.3 rad a step, and with pieces of 5 b at half the step
# Usage: tools/exact_chain.sh [folded-free|folded-table|coil [SCENE ...]|thin-converge]
#        (default: all but thin-converge)
# JOINTS=impulse or JOINTS=multibody runs the folded chain on rapier's joints instead of the
# exact chain; ENGINES=exact or ENGINES=rapier (default rapier,exact) picks the coil's engines.
# Runs two at a time; the engine times are per run, so they share the machine's cores.
set -euo pipefail
joints=${JOINTS:-exact}
engines=${ENGINES:-rapier,exact}
cd "$(dirname "$0")/.."
cargo build --release --locked --quiet
bin=target/release/uncoil
scene=scenes/validation/folded-chain.toml
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT

folded_free() {
  echo "### The folded chain, joints $joints, no floor (dt 5e-5 s)"
  echo
  echo "| links | t error at 0.25 / 0.5 / 0.75 / 0.9 L | joints / released at 0.9 L | numerical at 0.9 L | engine time |"
  echo "|---|---|---|---|---|"
  for n in 50 200 500 2000; do
    "$bin" run "$scene" --set solver.joints=$joints --set chain.links=$n \
      --out "$out/free-$n" > /dev/null 2>&1 || true
    python3 - "$out/free-$n/report.json" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))["report"]
c = {round(x["fraction"], 2): x for x in r["crossings"]}
errs = " / ".join(f"{100 * (c[f]['t_s'] / c[f]['t_closed_s'] - 1):+.3f}" for f in (0.25, 0.5, 0.75, 0.9))
j = c[0.9]
print(f"| {r['links']} | {errs} % | {100 * j['joints_j'] / j['released_j']:.4f} % | "
      f"{100 * j['numerical_j'] / j['released_j']:.4f} % | {r['wall_time_s']:.2f} s |")
PY
  done
  echo
}

folded_table() {
  echo "### Onto a table, joints $joints, 8 pin heights 0.70-0.84 L, to rest or 1 s (mean and standard error)"
  echo
  echo "| links | step | floor normal | friction | numerical | missed steps | engine time a run |"
  echo "|---|---|---|---|---|---|---|"
  for n in 50 200; do
    for dt in 5e-5 2.5e-5; do
      for h in 0.70 0.72 0.74 0.76 0.78 0.80 0.82 0.84; do
        echo "$bin run $scene --set solver.joints=$joints --set chain.links=$n --set solver.dt_s=$dt \
--set floor.enabled=true --set pin.height_m=$h --set stop.max_time_s=1 --out $out/table-$n-$dt-$h"
      done | xargs -P 2 -I{} sh -c '{} > /dev/null 2>&1 || true'
      python3 - "$out" "$n" "$dt" <<'PY'
import glob, json, statistics as st, sys
out, n, dt = sys.argv[1:]
rs = [json.load(open(p))["report"] for p in sorted(glob.glob(f"{out}/table-{n}-{dt}-*/report.json"))]
def ms(xs):
    m = st.mean(xs); return f"{100 * m:.2f} ± {100 * st.stdev(xs) / len(xs) ** 0.5:.2f} %"
share = lambda r, k: r["ledger"][k] / r["released_j"]
num = [(abs(r["ledger"]["joints_j"]) + abs(r["ledger"]["residual_j"])) / r["released_j"] for r in rs]
missed = sum(r["solve"]["missed_steps"] for r in rs)
wall = st.median(r["wall_time_s"] for r in rs)
print(f"| {n} | {dt} s | {ms([share(r, 'floor_normal_j') for r in rs])} | "
      f"{ms([share(r, 'floor_friction_j') for r in rs])} | {ms(num)} | {missed} | {wall:.1f} s |")
PY
    done
  done
  echo
}

coil() {
  for name in "$@"; do
    # The pushes of docs/final-bang.md's ensembles: the scene's own push and 7 just above it.
    case $name in
      thin-tape) pushes=0.100,0.101,0.102,0.103,0.104,0.105,0.106,0.107 ;;
      *) pushes=0.300,0.301,0.302,0.303,0.304,0.305,0.306,0.307 ;;
    esac
    # A run a guard stopped is a row of the sweep (its status column says why), not the
    # end of the script: the sweep then exits 3, and the ensemble is still summarised.
    "$bin" sweep "scenes/$name.toml" --vary push.contact_speed_m_s=$pushes \
      --vary solver.bang_engine=$engines --jobs 2 --quiet --out "$out/coil-$name" \
      > /dev/null || echo "($name: some runs did not complete; their rows say why)" >&2
    echo "### $name: 8 pushes on each bang engine (mean and standard error)"
    echo
    python3 - "$out/coil-$name/sweep.csv" "$engines" <<'PY'
import csv, statistics as st, sys
rows = list(csv.DictReader(open(sys.argv[1])))
print("| engine | floor normal | friction | freezing | numerical | bang wall / unroll wall |")
print("|---|---|---|---|---|---|")
for eng in sys.argv[2].split(","):
    rs = [r for r in rows if r["solver.bang_engine"] == eng and r["status"] == "ok"]
    if len(rs) < len([r for r in rows if r["solver.bang_engine"] == eng]):
        print(f"({eng}: {len(rs)} runs completed; the others are left out)")
    def ms(k, scale=100, unit=" %"):
        xs = [float(r[k]) for r in rs]
        return f"{scale * st.mean(xs):.2f} ± {scale * st.stdev(xs) / len(xs) ** 0.5:.2f}{unit}"
    ratio = [(float(r["wall_s"]) - float(r["wall_rolling_s"])) / float(r["wall_rolling_s"]) for r in rs]
    print(f"| {eng} | {ms('bang_floor_normal_of')} | {ms('bang_floor_friction_of')} | "
          f"{ms('bang_freeze_of')} | {ms('bang_numerical_of')} | "
          f"{st.mean(ratio):.2f} ± {st.stdev(ratio) / len(ratio) ** 0.5:.2f} |")
PY
    echo
  done
}

# The thin tape's split against its piece length and its step, on the exact chain.
thin_converge() {
  pushes=0.100,0.101,0.102,0.103,0.104,0.105,0.106,0.107
  "$bin" sweep scenes/thin-tape.toml --vary push.contact_speed_m_s=$pushes \
    --vary solver.bang_piece_m=1e-4,2e-4,5e-4 --jobs 2 --quiet --out "$out/thin-pieces" \
    > /dev/null || echo "(pieces: some runs did not complete; their rows say why)" >&2
  "$bin" sweep scenes/thin-tape.toml --vary push.contact_speed_m_s=$pushes \
    --vary solver.bang_step_rad=0.15 --jobs 2 --quiet --out "$out/thin-step" \
    > /dev/null || echo "(step: some runs did not complete; their rows say why)" >&2
  echo "### The thin tape on the exact chain: 8 pushes a setting (mean and standard error)"
  echo
  python3 - "$out/thin-pieces/sweep.csv" "$out/thin-step/sweep.csv" <<'PY'
import csv, statistics as st, sys
print("| piece | step | runs | floor normal | friction | freezing | numerical | bang wall / unroll wall |")
print("|---|---|---|---|---|---|---|---|")
def line(rs, piece, step):
    ok = [r for r in rs if r["status"] == "ok"]
    def ms(k):
        xs = [100 * float(r[k]) for r in ok]
        return f"{st.mean(xs):.2f} ± {st.stdev(xs) / len(xs) ** 0.5:.2f} %"
    ratio = [(float(r["wall_s"]) - float(r["wall_rolling_s"])) / float(r["wall_rolling_s"]) for r in ok]
    print(f"| {piece} | {step} | {len(ok)} of {len(rs)} | {ms('bang_floor_normal_of')} | "
          f"{ms('bang_floor_friction_of')} | {ms('bang_freeze_of')} | {ms('bang_numerical_of')} | "
          f"{st.median(ratio):.2f} (median) |")
pieces = list(csv.DictReader(open(sys.argv[1])))
for piece, label in (("1e-4", "b"), ("2e-4", "2 b"), ("5e-4", "5 b")):
    line([r for r in pieces if r["solver.bang_piece_m"] == piece], label, "0.3 rad")
line(list(csv.DictReader(open(sys.argv[2]))), "5 b", "0.15 rad")
PY
  echo
}

what=${1:-all}
case $what in
  folded-free) folded_free ;;
  folded-table) folded_table ;;
  coil) shift; coil "${@:-yoga-mat}" ;;
  thin-converge) thin_converge ;;
  all) folded_free; folded_table; coil yoga-mat ;;
  *) echo "usage: $0 [folded-free|folded-table|coil [SCENE ...]|thin-converge]" >&2; exit 2 ;;
esac
