#!/usr/bin/env bash
# The speed-against-error figures of docs/speed.md and docs/final-bang.md, written to docs/sweeps/<study>/
# (sweep.csv, report.md and the SVGs). Each study is one `uncoil sweep` and one
# `uncoil sweep-report`; runs go one at a time (--jobs 1) so that each run's wall time is
# its own, not shared with another run.
# Usage: tools/sweeps.sh [STUDY ...]   (default: all; the thin tape's two bang studies
#                                       take 14 minutes of it on 2 cores)
#        REPORT_ONLY=1 tools/sweeps.sh [STUDY ...]   redraws the reports from the sweep.csv files
#   yoga-pareto   yoga mat: resolution x adaptive step rule x solver iterations
#   yoga-links    yoga mat: convergence in the resolution (links per turn)
#   yoga-dt       yoga mat: convergence in the largest time step (max_dt_s, 1 step per link)
#   yoga-rule     yoga mat: convergence in the adaptive step rule (steps per link)
#   yoga-rule-fine  the same at 256 links per turn, where the resolution's own error
#                 (0.002 %) no longer hides the step's against the exact model
#   yoga-iter     yoga mat: convergence in the solver iterations
#   thin-pareto   thin tape: resolution x time step, against eq. (7)
#   scaling       both scenes: wall time per step and per simulated second against links
#   bang-links    yoga mat's final bang against the resolution (links per turn)
#   bang-step     ... against its step (solver.bang_step_rad)
#   bang-iter     ... against its solver iterations (solver.bang_iterations)
#   bang-substeps ... its substeps (24, 48, 96) against its step (0.15, 0.075, 0.0375 rad)
#   bang-relax    ... its relax sweeps per substep (1, 2, 4) against its step
#   bang-piece    ... against the length of its pieces (solver.bang_piece_m)
#   bang-turns    ... released with one turn left (r = b, the shipped scene) or two (r = 2b)
#                 (each setting an ensemble of 8 pushes, 0.300-0.307 m/s: the bang is chaotic)
#   bang-thin-piece  thin tape's final bang against the length of its pieces (b, 3b, 5b, 10b)
#   bang-thin-iter   ... against its substeps (solver.bang_iterations 24, 48, 96)
#                 (each setting an ensemble of 8 pushes, 0.100-0.107 m/s)
#   approach      yoga mat rolled to its last link: where x' stops diverging, against b and
#                 links per turn
#   yoga-run      the yoga mat's run plots (motion, energy, approach, forces) into docs/yoga-mat/
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --locked --quiet
bin=target/release/uncoil
docs=docs/sweeps
yoga=scenes/yoga-mat.toml
thin=scenes/thin-tape.toml
# The final bang is not part of the unroll that these figures are about: give it no time.
nobang=(--vary stop.bang_cap_s=0)
# The bang studies: eight pushes, 0.300 to 0.307 m/s, make each setting an ensemble.
pushes=(--vary push.contact_speed_m_s=0.300,0.301,0.302,0.303,0.304,0.305,0.306,0.307)
thin_pushes=(--vary push.contact_speed_m_s=0.100,0.101,0.102,0.103,0.104,0.105,0.106,0.107)
bang_report=(--repeat-key push.contact_speed_m_s --no-convergence)

study() { # name scene [sweep args...] -- [report args...]
  local name=$1 scene=$2
  shift 2
  local sweep_args=() report_args=()
  while [ $# -gt 0 ] && [ "$1" != "--" ]; do sweep_args+=("$1"); shift; done
  [ $# -gt 0 ] && shift
  report_args=("$@")
  echo "== $name" >&2
  if [ -z "${REPORT_ONLY:-}" ]; then
    # Exit 3: a guard stopped a run; its row says so and the report leaves it out.
    "$bin" sweep "$scene" --jobs 1 --quiet --out "$docs/$name" "${sweep_args[@]}" || [ $? -eq 3 ]
  fi
  rm -f "$docs/$name"/*.svg
  "$bin" sweep-report "$docs/$name/sweep.csv" "${report_args[@]}" > /dev/null
}

run_study() {
  case $1 in
  yoga-pareto)
    study yoga-pareto $yoga \
      --vary discretisation.links_per_turn=12,16,24,32,48,64,96 \
      --vary solver.steps_per_link=1,2,4,8 --vary solver.iterations=2,4,8 \
      --vary solver.max_dt_s=0.1 "${nobang[@]}" \
      -- --title "yoga mat" --no-convergence --target 0.003,0.3 ;;
  yoga-links)
    study yoga-links $yoga \
      --vary discretisation.links_per_turn=16,32,64,128,256 \
      --vary solver.steps_per_link=8 --vary solver.iterations=16 "${nobang[@]}" \
      -- --title "yoga mat, resolution" ;;
  yoga-dt)
    study yoga-dt $yoga \
      --vary discretisation.links_per_turn=32,64 --vary solver.steps_per_link=1 \
      --vary solver.iterations=8 \
      --vary solver.max_dt_s=0.02,0.01,0.005,0.0025,0.00125,0.000625 "${nobang[@]}" \
      -- --title "yoga mat, time step" --converge solver.max_dt_s ;;
  yoga-rule)
    study yoga-rule $yoga \
      --vary discretisation.links_per_turn=64 --vary solver.max_dt_s=0.1 \
      --vary solver.iterations=8 \
      --vary solver.steps_per_link=1,2,4,8,16 "${nobang[@]}" \
      -- --title "yoga mat, adaptive step rule" ;;
  yoga-rule-fine)
    study yoga-rule-fine $yoga \
      --vary discretisation.links_per_turn=256 --vary solver.max_dt_s=0.1 \
      --vary solver.iterations=8 \
      --vary solver.steps_per_link=1,2,4,8 "${nobang[@]}" \
      -- --title "yoga mat, adaptive step rule at 256 links per turn" ;;
  yoga-iter)
    study yoga-iter $yoga \
      --vary discretisation.links_per_turn=128 --vary solver.steps_per_link=8 \
      --vary solver.iterations=2,4,8,16,32 "${nobang[@]}" \
      -- --title "yoga mat, solver iterations" ;;
  thin-pareto)
    study thin-pareto $thin \
      --vary discretisation.links_per_turn=12,16,24,32,48 \
      --vary solver.max_dt_s=0.002,0.001,0.0005 "${nobang[@]}" \
      -- --title "thin tape" --reference eq7 --converge discretisation.links_per_turn \
      --target 0.01,15
    # The same runs against the exact-geometry model, the reference the runs converge to.
    rm -f "$docs/thin-pareto/vs-exact"/*.svg
    "$bin" sweep-report "$docs/thin-pareto/sweep.csv" --out "$docs/thin-pareto/vs-exact" \
      --title "thin tape" --reference exact --converge discretisation.links_per_turn > /dev/null ;;
  scaling)
    # Fixed dt = 1e-4 s (the adaptive rule never binds at 1 step per link), the first
    # 1 s; five repetitions (the scene name is a no-op key) give the spread.
    # Yoga mat: 11 turns, so 91, 909 and 4096 (the maximum) links per turn are about
    # 1k, 10k and 45k links. Thin tape: 300 turns, 7 (the fewest that fit the outer turn),
    # 33 and 333 links per turn are about 2.1k, 10k and 100k links.
    local fixed=(--vary solver.max_dt_s=0.0001 --vary solver.steps_per_link=1
                 --vary stop.max_time_s=1 --vary name=rep1,rep2,rep3,rep4,rep5)
    study scaling-yoga $yoga --vary discretisation.links_per_turn=91,909,4096 "${fixed[@]}" \
      -- --title "yoga mat, cost against links" --converge discretisation.links_per_turn \
      --repeat-key name
    study scaling-thin $thin --vary discretisation.links_per_turn=7,33,333 "${fixed[@]}" \
      -- --title "thin tape, cost against links" --converge discretisation.links_per_turn \
      --repeat-key name ;;
  bang-links)
    study bang-links $yoga "${pushes[@]}" --vary discretisation.links_per_turn=16,24,32,48,64 \
      -- --title "yoga mat, final bang, resolution" "${bang_report[@]}" ;;
  bang-step)
    study bang-step $yoga "${pushes[@]}" --vary solver.bang_step_rad=0.3,0.15,0.075,0.0375 \
      -- --title "yoga mat, final bang, step" "${bang_report[@]}" ;;
  bang-iter)
    study bang-iter $yoga "${pushes[@]}" --vary solver.bang_iterations=6,12,24,48 \
      -- --title "yoga mat, final bang, solver iterations" "${bang_report[@]}" ;;
  bang-substeps)
    study bang-substeps $yoga "${pushes[@]}" --vary solver.bang_iterations=24,48,96 \
      --vary solver.bang_step_rad=0.15,0.075,0.0375 \
      -- --title "yoga mat, final bang, substeps and step" "${bang_report[@]}" ;;
  bang-relax)
    study bang-relax $yoga "${pushes[@]}" --vary solver.bang_relax_iterations=1,2,4 \
      --vary solver.bang_step_rad=0.15,0.0375 \
      -- --title "yoga mat, final bang, relax sweeps and step" "${bang_report[@]}" ;;
  bang-piece)
    study bang-piece $yoga "${pushes[@]}" \
      --vary solver.bang_piece_m=0.01,0.005,0.0025,0.00125 \
      -- --title "yoga mat, final bang, length of its pieces" "${bang_report[@]}" ;;
  bang-turns)
    study bang-turns $yoga "${pushes[@]}" --vary stop.bang_radius_m=0.01,0.005 \
      -- --title "yoga mat, final bang, turns left at the release" "${bang_report[@]}" ;;
  bang-thin-piece)
    study bang-thin-piece $thin "${thin_pushes[@]}" \
      --vary solver.bang_piece_m=0.0001,0.0003,0.0005,0.001 \
      -- --title "thin tape, final bang, length of its pieces" "${bang_report[@]}" ;;
  bang-thin-iter)
    study bang-thin-iter $thin "${thin_pushes[@]}" --vary solver.bang_iterations=24,48,96 \
      -- --title "thin tape, final bang, its substeps" "${bang_report[@]}" ;;
  approach)
    # Rolled to the last link (a bang radius of 1 um): nothing cuts the approach short but
    # the coil itself.
    study approach $yoga --vary tape.thickness_m=0.0025,0.005,0.01 \
      --vary discretisation.links_per_turn=16,32,64,128 \
      --vary stop.bang_radius_m=0.000001 --vary stop.bang_cap_s=0 \
      -- --title "yoga mat, approach to the bang" --no-convergence ;;
  yoga-run)
    echo "== yoga-run" >&2
    "$bin" run $yoga --out runs/yoga-mat > /dev/null
    "$bin" plot runs/yoga-mat > /dev/null
    mkdir -p docs/yoga-mat
    cp runs/yoga-mat/motion.svg runs/yoga-mat/energy.svg runs/yoga-mat/approach.svg runs/yoga-mat/forces.svg \
      docs/yoga-mat/ ;;
  *) echo "unknown study $1" >&2; exit 2 ;;
  esac
}

all=(yoga-pareto yoga-links yoga-dt yoga-rule yoga-rule-fine yoga-iter thin-pareto scaling
     bang-links bang-step bang-iter bang-substeps bang-relax bang-piece bang-turns bang-thin-piece bang-thin-iter approach
     yoga-run)
for s in "${@:-${all[@]}}"; do run_study "$s"; done
