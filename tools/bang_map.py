#!/usr/bin/env python3
"""The bang's map across tapes, as docs/bang-map.md states it, from the study's sweep.csv.

    tools/bang_map.py docs/bang-map/sweep.csv

Groups the runs by tape (thickness over radius, core) and friction, the pushes pooled, and
prints Markdown: per point the runs, how they ended, each share of what the bang dissipated
over the runs that ran to their end (mean ± standard error; a numerical share above 1 % in
size marked (!)), what was left
moving, the most energy any run gained above E0 (of the energy scale; the guard stops a run
at 1e-2) and the mean wall time of a run; then least-squares fits of the friction share against the
friction coefficient, share = a mu^p, per tape, with their standard errors. Only the
Python standard library.
"""

import csv
import math
import sys
from collections import defaultdict

SHARES = [
    ("floor impacts", "bang_floor_normal_of"),
    ("floor friction", "bang_floor_friction_of"),
    ("layers' impacts", "bang_layers_normal_of"),
    ("layers' friction", "bang_layers_friction_of"),
    ("freezing", "bang_freeze_of"),
    ("numerical", "bang_numerical_of"),
    ("still moving", "bang_still_moving_of"),
]
MARK = 0.01


def number(cell: str) -> float:
    try:
        return float(cell)
    except ValueError:
        return math.nan


def mean_se(values: list[float]) -> tuple[float, float]:
    v = [x for x in values if math.isfinite(x)]
    if not v:
        return math.nan, math.nan
    m = sum(v) / len(v)
    if len(v) < 2:
        return m, math.nan
    return m, math.sqrt(sum((x - m) ** 2 for x in v) / (len(v) - 1) / len(v))


def percent(m: float, s: float) -> str:
    if not math.isfinite(m):
        return "-"
    return f"{100 * m:.1f} ± {100 * s:.1f}" if math.isfinite(s) else f"{100 * m:.1f}"


def ended(rows: list[dict]) -> str:
    counts: dict[str, int] = defaultdict(int)
    for r in rows:
        status = r["status"].split(":")[0]
        counts[r["bang_ended_by"] or status] += 1
    return ", ".join(f"{n} {k}" for k, n in sorted(counts.items()))


def fit_power(xs: list[float], ys: list[float], ses: list[float]) -> str:
    """share = a mu^p by weighted least squares in log-log; p and a with standard errors."""
    pts = [(math.log(x), math.log(y), s / y) for x, y, s in zip(xs, ys, ses) if y > 0 and s > 0]
    if len(pts) < 3:
        return "too few points"
    w = [1 / e**2 for _, _, e in pts]
    sw = sum(w)
    mx = sum(wi * x for wi, (x, _, _) in zip(w, pts)) / sw
    my = sum(wi * y for wi, (_, y, _) in zip(w, pts)) / sw
    sxx = sum(wi * (x - mx) ** 2 for wi, (x, _, _) in zip(w, pts))
    p = sum(wi * (x - mx) * (y - my) for wi, (x, y, _) in zip(w, pts)) / sxx
    c = my - p * mx
    chi2 = sum(wi * (y - c - p * x) ** 2 for wi, (x, y, _) in zip(w, pts))
    dof = len(pts) - 2
    scale = max(1.0, chi2 / dof) if dof > 0 else 1.0
    p_se = math.sqrt(scale / sxx)
    return f"p = {p:.2f} ± {p_se:.2f}, a = {math.exp(c):.3f}, chi2/dof = {chi2 / max(dof, 1):.1f}"


def main() -> None:
    if len(sys.argv) != 2 or sys.argv[1] in ("-h", "--help"):
        print(__doc__)
        raise SystemExit(0 if len(sys.argv) == 2 else 2)
    with open(sys.argv[1], newline="") as f:
        rows = list(csv.DictReader(f))
    points: dict[tuple, list[dict]] = defaultdict(list)
    for r in rows:
        tape = (number(r["tape.thickness_m"]), number(r["tape.core_radius_m"]))
        points[(tape, number(r["floor.friction"]))].append(r)
    radius = 0.03
    print("| b/R | core | friction | runs | ended | " + " | ".join(n for n, _ in SHARES) + " | most energy gained | run wall s |")
    print("|---|---|---|---|---|" + "---|" * len(SHARES) + "---|---|")
    fits: dict[tuple, tuple[list, list, list]] = defaultdict(lambda: ([], [], []))
    for (tape, mu), rs in sorted(points.items()):
        cells = []
        marked = False
        # The shares of the runs that ran to their end: a run a guard stopped in its bang
        # has booked only part of it.
        done = [r for r in rs if r["status"] == "ok"]
        for name, col in SHARES:
            m, s = mean_se([number(r.get(col, "")) for r in done])
            if name == "numerical" and abs(m) > MARK:
                marked = True
            cells.append(percent(m, s))
            if name == "floor friction" and mu > 0:
                fits[tape][0].append(mu)
                fits[tape][1].append(m)
                fits[tape][2].append(s)
        wall, _ = mean_se([number(r["wall_s"]) for r in rs])
        rise = max(number(r["max_energy_rise_rel"]) for r in rs)
        core = "R/2" if tape[1] > 0 else "0"
        print(
            f"| 1/{radius / tape[0]:.0f} | {core} | {mu:g}{' (!)' if marked else ''} | {len(rs)} | "
            f"{ended(rs)} | " + " | ".join(cells) + f" | {rise:.1e} | {wall:.3g} |"
        )
    print()
    print("Friction share against the friction coefficient (mu > 0), share = a mu^p:")
    print()
    for tape, (mu, share, se) in sorted(fits.items()):
        core = "R/2" if tape[1] > 0 else "0"
        low = [(x, y, s) for x, y, s in zip(mu, share, se) if x <= 0.6]
        print(
            f"- b/R = 1/{radius / tape[0]:.0f}, core {core}: mu 0.1-0.6: "
            f"{fit_power(*map(list, zip(*low)))}; mu 0.1-1.5: {fit_power(mu, share, se)}"
        )
    def wall(rs: list[dict]) -> float:
        return sum(number(r["wall_s"]) for r in rs if math.isfinite(number(r["wall_s"])))

    sliding = [r for r in rows if number(r["floor.friction"]) > 0]
    frictionless = [r for r in rows if number(r["floor.friction"]) == 0]
    print()
    print(
        f"{len(rows)} runs, {wall(rows):.0f} s of run wall time in all: "
        f"{len(sliding)} with friction, {wall(sliding):.0f} s; "
        f"{len(frictionless)} frictionless, {wall(frictionless):.0f} s."
    )


if __name__ == "__main__":
    main()
