#!/usr/bin/env python3
"""Runs `uncoil run scenes/yoga-mat.toml` and each peer side by side, in alternating rounds
(round robin, the order rotated every round), times each whole process, and writes
docs/peers.md's table (between its PEERS-TABLE markers) and docs/peers.svg (wall time
against error). Builds nothing: `cargo build --release --example plain-rapier` first.

    python tools/peers/compare.py [--rounds 5] [--only uncoil,mujoco]
"""

from __future__ import annotations

import argparse
import csv
import json
import pathlib
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

REPO = pathlib.Path(__file__).resolve().parents[2]
PEERS = pathlib.Path(__file__).resolve().parent
SCENE = REPO / "scenes" / "yoga-mat.toml"
FRACTIONS = (0.4375, 0.75, 0.9)


def commands(python: str) -> dict:
    return {
        "uncoil": None,  # run by uncoil_run: its output folder is read afterwards
        "plain-rapier": [str(REPO / "target/release/examples/plain-rapier")],
        # A run to f = 0.9 at its defaults takes well over 10 minutes on 2 cores.
        "mujoco": [python, str(PEERS / "mujoco_mat.py"), "--max-wall-s", "600"],
        "pymunk": [python, str(PEERS / "pymunk_mat.py")],
    }


def uncoil_run(tmp: pathlib.Path) -> tuple[float, dict]:
    """uncoil as shipped (its MCAP too), into a fresh folder; its errors and energy at the
    fractions, read from samples.csv (sampled every 1 ms, interpolated linearly)."""
    out = tmp / f"uncoil-{time.monotonic_ns()}"
    tick = time.perf_counter()
    subprocess.run([str(REPO / "target/release/uncoil"), "run", str(SCENE), "--out", str(out)],
                   check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    wall_s = time.perf_counter() - tick
    report = json.loads((out / "report.json").read_text())
    with open(out / "samples.csv") as fh:
        rows = list(csv.DictReader(fh))
    t = np.array([float(r["t_s"]) for r in rows])
    f = np.array([float(r["laid_fraction"]) for r in rows])
    e = np.array([float(r["kinetic_j"]) + float(r["potential_j"]) for r in rows])
    import uncoil
    import uncoil.theory

    scene = uncoil.load_scene(str(SCENE))
    flat_j = scene_flat_j()
    e0 = e[0] - flat_j
    ms = []
    for target in FRACTIONS:
        k = int(np.argmax(f >= target))
        s = (target - f[k - 1]) / (f[k] - f[k - 1])
        tk = t[k - 1] + s * (t[k] - t[k - 1])
        ek = e[k - 1] + s * (e[k] - e[k - 1]) - flat_j
        te = float(uncoil.theory.exact_time_at_fraction(scene, target))
        ms.append({"f": target, "t_s": tk, "exact_s": te, "error_pct": 100 * (tk - te) / te,
                   "lost_pct": 100 * (e0 - ek) / e0})
    return wall_s, {"peer": "uncoil", "stepping_s": report["wall_time_s"],
                    "outcome": "completed", "milestones": ms, "settings": "scene as shipped"}


def scene_flat_j() -> float:
    import tomllib

    tape = tomllib.loads(SCENE.read_text())["tape"]
    g = tomllib.loads(SCENE.read_text()).get("gravity", {}).get("g_m_s2", 9.81)
    return tape["mass_kg"] * g * 0.5 * tape["thickness_m"]


def peer_run(cmd: list) -> tuple[float, dict]:
    tick = time.perf_counter()
    done = subprocess.run(cmd, check=True, capture_output=True, text=True)
    wall_s = time.perf_counter() - tick
    return wall_s, json.loads(done.stdout.strip().splitlines()[-1])


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--rounds", type=int, default=5)
    p.add_argument("--only", default=None, help="comma-separated subset of the runs")
    p.add_argument("--once", default="",
                   help="comma-separated runs too slow to repeat: run in the first round only")
    p.add_argument("--no-write", action="store_true", help="print only; leave docs/ alone")
    args = p.parse_args()
    cmds = commands(sys.executable)
    names = [n for n in cmds if args.only is None or n in args.only.split(",")]
    walls = {n: [] for n in names}
    last = {}
    with tempfile.TemporaryDirectory() as tmp:
        for r in range(args.rounds):
            for i in range(len(names)):
                name = names[(r + i) % len(names)]
                if r > 0 and name in args.once.split(","):
                    continue
                wall_s, result = (uncoil_run(pathlib.Path(tmp)) if name == "uncoil"
                                  else peer_run(cmds[name]))
                walls[name].append(wall_s)
                last[name] = result
                print(f"round {r + 1}: {name} {wall_s:.3f} s", file=sys.stderr, flush=True)
    rows = []
    for name in names:
        w, res = walls[name], last[name]
        m = {round(x["f"], 4): x for x in res["milestones"]}
        rows.append({"name": name, "median_s": statistics.median(w), "min_s": min(w),
                     "max_s": max(w), "stepping_s": res["stepping_s"], "outcome": res["outcome"],
                     "settings": res.get("settings"), "m": m})
    table = markdown(rows, args.rounds, args.once)
    print(table)
    print(json.dumps(rows))
    if not args.no_write:
        write_doc(table)
        plot(rows, REPO / "docs" / "peers.svg")


def cell(x, fmt="{:+.2f}") -> str:
    return "-" if x is None else fmt.format(x)


def markdown(rows: list, rounds: int, once: str) -> str:
    head = ("| run | wall s, median (min-max) | engine s | err 0.4375 | err 0.75 | err 0.9 "
            "| lost 0.4375 | lost 0.75 | lost 0.9 | outcome |\n" + "|---" * 10 + "|\n")
    body = ""
    for r in rows:
        m = [r["m"].get(f, {}) for f in FRACTIONS]
        errs = " | ".join(cell(x.get("error_pct")) + ("%" if x.get("error_pct") is not None else "")
                          for x in m)
        lost = " | ".join(cell(x.get("lost_pct"), "{:.2f}") + ("%" if x.get("lost_pct") is not None else "")
                          for x in m)
        body += (f"| {r['name']} | {r['median_s']:.3f} ({r['min_s']:.3f}-{r['max_s']:.3f}) "
                 f"| {r['stepping_s']:.3f} | {errs} | {lost} | {r['outcome']} |\n")
    note = f" ({once} in the first round only)" if once else ""
    return (head + body + f"\n{rounds} alternating rounds{note}; error = (t - t_exact) / t_exact; "
            "lost = % of E0 above flat, at the step that crossed.\n")


def write_doc(table: str) -> None:
    doc = REPO / "docs" / "peers.md"
    text = doc.read_text()
    start, end = "<!-- PEERS-TABLE -->", "<!-- /PEERS-TABLE -->"
    a, b = text.index(start) + len(start), text.index(end)
    doc.write_text(text[:a] + "\n" + table + text[b:])


def plot(rows: list, path: pathlib.Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    markers = {"uncoil": "o", "plain-rapier": "s", "mujoco": "^", "pymunk": "D"}
    for r in rows:
        m = r["m"].get(0.75, {})
        err = m.get("error_pct")
        if err is None:
            # Never reached f = 0.75: drawn hollow at 100 %, its outcome in the legend.
            ax.errorbar(r["median_s"], 100.0, xerr=[[r["median_s"] - r["min_s"]], [r["max_s"] - r["median_s"]]],
                        marker=markers.get(r["name"], "o"), mfc="none", ls="none",
                        label=f"{r['name']}: {r['outcome']}")
            continue
        ax.errorbar(r["median_s"], abs(err), xerr=[[r["median_s"] - r["min_s"]], [r["max_s"] - r["median_s"]]],
                    marker=markers.get(r["name"], "o"), ls="none", label=r["name"])
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("whole-process wall time, s (median; bar: min-max)")
    ax.set_ylabel("|time error| at laid fraction 0.75, %")
    ax.set_title("yoga mat: uncoil and its peers")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path)


if __name__ == "__main__":
    main()
