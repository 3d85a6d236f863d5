#!/usr/bin/env bash
# The Slurm array-job test: on a single-node Slurm cluster (tools/slurm/cluster.sh), a small
# sweep runs as a 2-task array job (tools/slurm/sweep.sbatch, `sbatch --wait`), its shards
# are merged, and the merged sweep.csv must equal the same sweep run locally in every column
# but the wall times; then a task's shard file is cut inside its last row, and, with slower
# runs, a task is cancelled (`scancel`) mid-run; each time the array job submitted again
# resumes, and the merge is the local sweep's. Needs root (the cluster) and a built binary.
# Usage: tools/slurm/test.sh [UNCOIL_BINARY]   (default: target/release/uncoil)
set -euo pipefail
cd "$(dirname "$0")/../.."
bin=$(realpath "${1:-target/release/uncoil}")
[ -x "$bin" ] || { echo "error: no binary at $bin (cargo build)" >&2; exit 1; }
tools/slurm/cluster.sh start
work=$(mktemp -d /var/tmp/uncoil-slurm-test.XXXXXX)
trap 'rm -rf "$work"' EXIT
scene=$(realpath scenes/yoga-mat.toml)
# Three settings, no final bang: seconds each.
vary="--vary discretisation.links_per_turn=8,12,16 --vary stop.bang_cap_s=0"
array_job() {
  SCENE=$scene OUT=$work/slurm UNCOIL=$bin VARY=$vary \
    sbatch --wait --array=1-2 --chdir="$work" --job-name=uncoil-sweep-test tools/slurm/sweep.sbatch
  cat "$work"/uncoil-sweep-*.out
  rm -f "$work"/uncoil-sweep-*.out
  "$bin" sweep --merge "$work"/slurm/sweep.*-of-2.csv --out "$work/slurm"
}
# compare MERGED LOCAL LABEL RUNS
compare() {
  python3 - "$@" <<'PY'
import csv, sys

def rows(path):
    with open(path, newline="") as f:
        return sorted(csv.DictReader(f), key=lambda r: int(r["index"]))

merged, local = rows(sys.argv[1]), rows(sys.argv[2])
wall = {"wall_s", "wall_rolling_s"}
n = int(sys.argv[4])
assert len(merged) == len(local) == n, (len(merged), len(local), n)
assert list(merged[0]) == list(local[0]), "the columns differ"
for m, l in zip(merged, local):
    differ = [k for k in m if k not in wall and m[k] != l[k]]
    assert not differ, f"run {m['index']}: {differ} differ"
print(f"slurm array job{sys.argv[3]}: {len(merged)} runs merged from 2 shards match the "
      f"local sweep in all {len(merged[0]) - len(wall)} columns but the wall times")
PY
}
array_job
# shellcheck disable=SC2086 # vary holds several arguments.
"$bin" sweep "$scene" $vary --quiet --jobs 1 --out "$work/local"
compare "$work/slurm/sweep.csv" "$work/local/sweep.csv" "" 3
# A task killed while writing: its shard file cut inside its last row. The array job run
# again resumes: the cut row's run goes again, the others are kept, and the merge is the same.
python3 - "$work/slurm/sweep.1-of-2.csv" <<'PY'
import sys
path = sys.argv[1]
text = open(path).read().rstrip("\n")
open(path, "w").write(text[: len(text) - 5])
PY
array_job | tee "$work/resumed.txt"
grep -q "kept from before" "$work/resumed.txt"
compare "$work/slurm/sweep.csv" "$work/local/sweep.csv" ", killed and resumed" 3

# A task cancelled mid-run (scancel: SIGTERM to the batch step, which is uncoil, `exec`ed):
# runs of about 4 s, two a task. Once task 1 has written its first row, it is cancelled; its
# run in progress stops, its row says interrupted and its files are finished. Submitted
# again, task 1 runs that one again and task 2, finished, keeps its rows.
slow="--vary discretisation.links_per_turn=8,12,16,24 --vary solver.max_dt_s=1e-5 --vary stop.bang_cap_s=0"
job=$(SCENE=$scene OUT=$work/cancel UNCOIL=$bin VARY=$slow \
  sbatch --parsable --array=1-2 --chdir="$work" --job-name=uncoil-cancel-test tools/slurm/sweep.sbatch)
job=${job%%;*}
shard=$work/cancel/sweep.1-of-2.csv
rows() { if [ -f "$1" ]; then wc -l < "$1"; else echo 0; fi; }
for _ in $(seq 1200); do [ "$(rows "$shard")" -ge 2 ] && break; sleep 0.1; done
[ "$(rows "$shard")" -ge 2 ] || { echo "error: task 1 wrote no row in 120 s" >&2; exit 1; }
scancel "${job}_1"
for _ in $(seq 1200); do squeue -h -j "$job" | grep -q . || break; sleep 0.1; done
if squeue -h -j "$job" | grep -q .; then echo "error: job $job still queued" >&2; exit 1; fi
grep -h "interrupted by SIGTERM" "$work"/uncoil-sweep-"${job}"_1.out
python3 - "$shard" <<'PY'
import csv, sys
with open(sys.argv[1], newline="") as f:
    status = [r["status"] for r in csv.DictReader(f)]
assert status.count("interrupted") == 1 and len(status) == 2, status
print(f"task 1 cancelled mid-run: its rows say {status}")
PY
rm -f "$work"/uncoil-sweep-*.out
SCENE=$scene OUT=$work/cancel UNCOIL=$bin VARY=$slow \
  sbatch --wait --array=1-2 --chdir="$work" --job-name=uncoil-cancel-test tools/slurm/sweep.sbatch
cat "$work"/uncoil-sweep-*.out | tee "$work/cancelled.txt"
grep -q "1 run (0 failed, 0 stopped by a guard, 1 kept from before)" "$work/cancelled.txt"
"$bin" sweep --merge "$work"/cancel/sweep.*-of-2.csv --out "$work/cancel"
# shellcheck disable=SC2086 # slow holds several arguments.
"$bin" sweep "$scene" $slow --quiet --jobs 1 --out "$work/cancel-local"
compare "$work/cancel/sweep.csv" "$work/cancel-local/sweep.csv" ", cancelled and resumed" 4
