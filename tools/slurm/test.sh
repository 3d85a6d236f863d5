#!/usr/bin/env bash
# The Slurm array-job test: on a single-node Slurm cluster (tools/slurm/cluster.sh), a small
# sweep runs as a 2-task array job (tools/slurm/sweep.sbatch, `sbatch --wait`), its shards
# are merged, and the merged sweep.csv must equal the same sweep run locally in every column
# but the wall times. Needs root (the cluster) and a built binary.
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
compare() {
  python3 - "$work/slurm/sweep.csv" "$work/local/sweep.csv" "$1" <<'PY'
import csv, sys

def rows(path):
    with open(path, newline="") as f:
        return sorted(csv.DictReader(f), key=lambda r: int(r["index"]))

merged, local = rows(sys.argv[1]), rows(sys.argv[2])
wall = {"wall_s", "wall_rolling_s"}
assert len(merged) == len(local) == 3, (len(merged), len(local))
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
compare ""
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
compare ", killed and resumed"
