#!/usr/bin/env python3
"""When in the final bang the floor's impulses do their work: the slam, then the rest.

Reads run folders written with a sample at every step (`uncoil run SCENE --set
output.sample_interval_s=0 --out DIR`) and splits what the bang's floor impulses did
(`bang_floor_normal_j`, `bang_floor_friction_j` in samples.csv) at the moment the moving
tape's kinetic energy first falls to half of what the bang received: the slam of the last
turn onto the floor, then the rest (the landings that follow and the sliding to rest).

For each folder it prints one CSV row: the push, the time of that moment after the release,
the share of the normal and of the friction work done by then, and the share of friction's
work done in steps where the normal impulses did work too (an impact's friction, as against
sliding under the tape's weight alone), and the share of the bang's steps that are such
impact steps. With several folders it ends with the mean and the
standard error of each column.

    tools/bang_phases.py runs/thin-*      # one folder per push
"""

import csv
import json
import math
import sys
from pathlib import Path

COLUMNS = [
    "push_m_s",
    "half_kinetic_at_s",
    "normal_by_then",
    "friction_by_then",
    "friction_in_impact_steps",
    "impact_steps",
]


def phases(folder: Path) -> list[float]:
    report = json.loads((folder / "report.json").read_text())
    start = report["ledger"]["bang_time_s"]
    if start is None:
        raise SystemExit(f"{folder}: the run has no final bang")
    with open(folder / "samples.csv", newline="") as f:
        rows = [r for r in csv.DictReader(f) if float(r["t_s"]) >= start]
    if len(rows) < 2:
        raise SystemExit(f"{folder}: no samples in the bang (sample_interval_s=0 keeps every step)")
    t = [float(r["t_s"]) - start for r in rows]
    normal = [float(r["bang_floor_normal_j"]) for r in rows]
    friction = [float(r["bang_floor_friction_j"]) for r in rows]
    kinetic = [float(r["kinetic_j"]) for r in rows]
    half = next(i for i, k in enumerate(kinetic) if k <= kinetic[0] / 2)
    # A step whose normal impulses did work is an impact: resting contact does none.
    tiny = 1e-9 * normal[-1]
    impacts = [i for i in range(1, len(rows)) if normal[i] - normal[i - 1] > tiny]
    in_impacts = sum(friction[i] - friction[i - 1] for i in impacts)
    return [
        report["scene"]["push"]["contact_speed_m_s"],
        t[half],
        normal[half] / normal[-1],
        friction[half] / friction[-1],
        in_impacts / friction[-1],
        len(impacts) / (len(rows) - 1),
    ]


def main() -> None:
    folders = [Path(a) for a in sys.argv[1:]]
    if not folders or any(a in ("-h", "--help") for a in sys.argv[1:]):
        print(__doc__)
        raise SystemExit(0 if folders else 2)
    out = csv.writer(sys.stdout)
    out.writerow(["folder", *COLUMNS])
    table = []
    for folder in folders:
        row = phases(folder)
        table.append(row)
        out.writerow([folder, *(f"{x:.4g}" for x in row)])
    if len(table) > 1:
        n = len(table)
        means = [sum(c) / n for c in zip(*table)]
        ses = [
            math.sqrt(sum((x - m) ** 2 for x in c) / (n - 1) / n)
            for c, m in zip(zip(*table), means)
        ]
        out.writerow(["mean", *(f"{m:.4g}" for m in means)])
        out.writerow(["standard error", *(f"{s:.2g}" for s in ses)])


if __name__ == "__main__":
    main()
