#!/usr/bin/env bash
# The falling folded chain's tables of docs/folded-chain.md: each joint set-up at 50, 200
# and 500 links, without a floor (to x = 0.95 L) and onto a table 0.75 L below the pin (to
# rest or 1 s), one run at a time; then the table case booked one substep per step. Prints
# Markdown tables; every figure is read from the runs' report.json.
# Usage: tools/folded_chain.sh [SETUP ...]   (default: all; about 10 minutes on 2 cores)
#   SETUP is NAME:KEY=VALUE,KEY=VALUE, e.g. relax4:solver.relax_iterations=4
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --locked --quiet
bin=target/release/uncoil
scene=scenes/validation/folded-chain.toml
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
setups=("$@")
[ ${#setups[@]} -gt 0 ] || setups=(
  "impulse:solver.substeps=24"
  "relax-4:solver.relax_iterations=4"
  "substeps-96:solver.substeps=96,solver.dt_s=5e-5"
)
run() { # dir args...
  local dir=$1
  shift
  "$bin" run "$scene" --out "$dir" "$@" > /dev/null 2>&1 || true
}
row() { # label report.json floor(0|1)
  python3 - "$1" "$2" "$3" <<'PY'
import json, sys
label, path, floor = sys.argv[1], sys.argv[2], sys.argv[3] == "1"
r = json.load(open(path))["report"]
pct = lambda v: f"{100 * v:.2f} %"
if not floor:
    c = {round(x["fraction"], 2): x for x in r["crossings"]}
    t75 = c.get(0.75)
    t_err = pct(t75["t_s"] / t75["t_closed_s"] - 1) if t75 else "-"
    j90 = pct(c[0.9]["numerical_j"] / c[0.9]["released_j"]) if 0.9 in c else "-"
    j95 = pct(c[0.95]["numerical_j"] / c[0.95]["released_j"]) if 0.95 in c else "-"
    print(f"| {label} | {r['links']} | {t_err} | {j90} | {j95} | {r['wall_time_s']:.2f} s |")
else:
    l, e = r["ledger"], r["released_j"]
    num = abs(l["joints_j"]) + abs(l["residual_j"])
    print(f"| {label} | {r['links']} | {pct(l['floor_normal_j'] / e)} | "
          f"{pct(l['floor_friction_j'] / e)} | {pct(num / e)} | {pct(r['kinetic_j'] / e)} | "
          f"{r['end']} | {r['wall_time_s']:.2f} s |")
PY
}
sets() { # "k=v,k=v" -> --set k=v --set k=v
  local IFS=,
  for kv in $1; do printf -- '--set\n%s\n' "$kv"; done
}
echo "### Without a floor, to x = 0.95 L"
echo
echo "| set-up | links | t(0.75 L) error | numerical / released at 0.9 L | at 0.95 L | engine time |"
echo "|---|---|---|---|---|---|"
for s in "${setups[@]}"; do
  name=${s%%:*}
  mapfile -t args < <(sets "${s#*:}")
  for n in 50 200 500; do
    run "$out/free-$name-$n" "${args[@]}" --set chain.links=$n
    row "$name" "$out/free-$name-$n/report.json" 0
  done
done
echo
echo "### Onto a table 0.75 L below the pin, to rest or 1 s (shares of the energy released)"
echo
echo "| set-up | links | floor normal | floor friction | numerical | kinetic left | end | engine time |"
echo "|---|---|---|---|---|---|---|---|"
table=(--set floor.enabled=true --set pin.height_m=0.75 --set stop.max_time_s=1.0)
for s in "${setups[@]}" "one-substep:solver.substeps=1,solver.dt_s=2.0833333333e-6" \
  "one-substep-relax-8:solver.substeps=1,solver.dt_s=2.0833333333e-6,solver.relax_iterations=8"; do
  name=${s%%:*}
  mapfile -t args < <(sets "${s#*:}")
  for n in 50 200 500; do
    case $name in one-substep*) [ $n -eq 200 ] || continue ;; esac
    run "$out/table-$name-$n" "${args[@]}" "${table[@]}" --set chain.links=$n
    row "$name" "$out/table-$name-$n/report.json" 1
  done
done
