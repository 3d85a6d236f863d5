"""What the Python peers share: the scene, the spiral uncoil builds its links on, the laid
fraction measured from the links' angles, the milestones and the report. It simulates
nothing; each peer builds its own engine's chain from `Mat.nodes()`.

The geometry follows src/spiral.rs: the midline `p(psi) = a psi (cos psi, -sin psi)` with
`a = b / (2 pi)` runs from radius b/2 to R - b/2; nodes divide every turn into equal angles
from the outer end inward; the outer end is at the bottom of the coil, on the floor at x = 0.
"""

from __future__ import annotations

import argparse
import json
import math
import pathlib
import time
import tomllib

import numpy as np

REPO = pathlib.Path(__file__).resolve().parents[2]
# 0.75R (f = 0.4375, uncoil's first milestone), 0.5R (0.75) and 0.9.
MILESTONES = (0.4375, 0.75, 0.9)


def wrap(a):
    """Angle(s) into (-pi, pi]."""
    return a - np.round(a / (2 * math.pi)) * 2 * math.pi


class Mat:
    """The scene's tape, wound: its spiral, its nodes and the exact model's milestone times."""

    def __init__(self, scene_path: pathlib.Path, links_per_turn: int | None):
        with open(scene_path, "rb") as fh:
            toml = tomllib.load(fh)
        tape = toml["tape"]
        self.outer_radius_m = tape["outer_radius_m"]
        self.thickness_m = tape["thickness_m"]
        self.mass_kg = tape["mass_kg"]
        if tape.get("core_radius_m", 0.0) != 0.0:
            raise SystemExit("the peers build a solid coil only (core_radius_m = 0)")
        self.friction = toml.get("floor", {}).get("friction", 1.0)
        self.g_m_s2 = toml.get("gravity", {}).get("g_m_s2", 9.81)
        self.push_m_s = toml["push"]["contact_speed_m_s"]
        self.links_per_turn = links_per_turn or toml.get("discretisation", {}).get(
            "links_per_turn", 32
        )
        b = self.thickness_m
        self.a_m = b / (2 * math.pi)
        self.psi_in = 0.5 * b / self.a_m
        self.psi_out = (self.outer_radius_m - 0.5 * b) / self.a_m
        self.length_m = self.arc_from_centre(self.psi_out) - self.arc_from_centre(self.psi_in)
        # The exact-geometry model's times, from the uncoil package (the crate's own numbers).
        import uncoil
        import uncoil.theory

        scene = uncoil.load_scene(str(scene_path))
        self.exact_s = [float(uncoil.theory.exact_time_at_fraction(scene, f)) for f in MILESTONES]

    def arc_from_centre(self, psi):
        return 0.5 * self.a_m * (psi * math.sqrt(1 + psi * psi) + math.asinh(psi))

    def point(self, psi):
        return np.array([self.a_m * psi * np.cos(psi), -self.a_m * psi * np.sin(psi)])

    def curvature_radius(self, psi):
        q = 1 + psi * psi
        return self.a_m * q * math.sqrt(q) / (1 + q)

    @staticmethod
    def rotation_with_bottom_at(psi):
        """Rotation (rad) that puts the spiral point `psi` at the bottom, laid tape to the left."""
        return math.pi + (psi + 0.5 * math.pi - math.atan(1 / psi))

    def lowest_psi(self, rotation, guess):
        """The spiral parameter at the bottom of a coil rotated by `rotation` (Newton)."""
        psi = guess
        for _ in range(30):
            err = wrap(self.rotation_with_bottom_at(psi) - rotation)
            step = err / ((2 + psi * psi) / (1 + psi * psi))
            psi -= step
            if abs(step) < 1e-13 * max(psi, 1.0):
                break
        return min(max(psi, self.psi_in), self.psi_out)

    def laid_fraction(self, psi_low):
        return 1 - (self.arc_from_centre(psi_low) - self.arc_from_centre(self.psi_in)) / self.length_m

    def nodes(self):
        """Node parameters and world positions (m, floor y = 0, laid midline at b/2), and the
        start: rotation of the spiral frame, the contact point and the clockwise spin (rad/s)."""
        step = 2 * math.pi / self.links_per_turn
        psis = [self.psi_out]
        k = 1
        while True:
            psi = self.psi_out - step * k
            if psi <= self.psi_in + 0.25 * step:
                psis.append(self.psi_in)
                break
            psis.append(psi)
            k += 1
        psis = np.array(psis)
        rot = self.rotation_with_bottom_at(self.psi_out)
        c, s = math.cos(rot), math.sin(rot)
        pts = self.point(psis)
        world = np.stack([c * pts[0] - s * pts[1], s * pts[0] + c * pts[1]], axis=1)
        contact = np.array([0.0, 0.5 * self.thickness_m])
        world += contact - world[0]
        # Rolling without slip about the contact: the exact model's start, omega = v / rho.
        omega = -self.push_m_s / self.curvature_radius(self.psi_out)
        return psis, world, rot, contact, omega


class LaidMeter:
    """The laid fraction from the links' world angles, as uncoil reads its coil's: the
    wound links keep their angles in the spiral's frame, so they give the coil's rotation,
    and the rotation the spiral parameter whose tangent is horizontal."""

    def __init__(self, mat: Mat, frame_angles_rad: np.ndarray):
        self.mat = mat
        self.frame_angles = frame_angles_rad
        self.quarter = max(mat.links_per_turn // 4, 2)
        self.threshold = 0.5 * 2 * math.pi / mat.links_per_turn
        self.first_wound = 0
        self.psi_low = mat.psi_out

    def __call__(self, angle_of) -> float:
        """`angle_of(lo, hi)`: world angles (rad) of links lo..hi-1 as a numpy array."""
        n = len(self.frame_angles)
        k = max(self.first_wound - 2, 0)
        while k + 1 < n:
            chunk = angle_of(k, min(k + 8, n))
            turned = np.nonzero(wrap(chunk) > self.threshold)[0]
            if len(turned):
                k += int(turned[0])
                break
            k += len(chunk)
        k = min(k, n - 1)
        self.first_wound = k
        lo, hi = k + 1, min(k + 1 + self.quarter, n)
        if lo >= hi:
            return 1.0
        rel = angle_of(lo, hi) - self.frame_angles[lo:hi]
        rotation = rel[0] + float(np.mean(wrap(rel - rel[0])))
        self.psi_low = self.mat.lowest_psi(rotation, self.psi_low)
        return self.mat.laid_fraction(self.psi_low)


class Recorder:
    """Milestone crossings (time interpolated in the step, energy at the step that crossed),
    stall and blow-up detection, and the printed and JSON report."""

    def __init__(self, name: str, mat: Mat, e0_j: float, stop_fraction: float,
                 max_wall_s: float = math.inf):
        self.name, self.mat, self.e0_j, self.stop_fraction = name, mat, e0_j, stop_fraction
        self.max_wall_s, self.started = max_wall_s, time.perf_counter()
        self.hits = [None] * len(MILESTONES)
        self.f_prev, self.f_best, self.t_best = 0.0, 0.0, 0.0
        self.t_limit_s = 3 * max(mat.exact_s)
        self.outcome = None

    def observe(self, t_s: float, dt_s: float, f: float, energy) -> bool:
        """Records a step; `energy()` is called only at crossings. True when the run ends."""
        for k, target in enumerate(MILESTONES):
            if self.hits[k] is None and self.f_prev < target <= f:
                s = (target - self.f_prev) / (f - self.f_prev)
                self.hits[k] = (t_s - dt_s * (1 - s), energy())
        self.f_prev = f
        if f > self.f_best + 1e-3:
            self.f_best, self.t_best = f, t_s
        if not math.isfinite(f):
            self.outcome = f"exploded at t = {t_s:.4f} s"
        elif f >= self.stop_fraction:
            self.outcome = "completed"
        elif time.perf_counter() - self.started > self.max_wall_s:
            self.outcome = f"out of wall time at laid fraction {f:.4f} (t = {t_s:.4f} s)"
        elif t_s - self.t_best > 1.0 or t_s > self.t_limit_s:
            self.outcome = f"stalled at laid fraction {self.f_best:.4f} (t = {self.t_best:.4f} s)"
        return self.outcome is not None

    def report(self, started: float, stepping_s: float, steps: int, t_s: float, settings: dict,
               links: int, max_gain_j: float | None = None) -> None:
        wall_s = time.perf_counter() - started
        print(f"{self.name}: {links} links ({self.mat.links_per_turn} per turn), {steps} steps, "
              f"{t_s:.4f} s simulated, settings {settings}")
        print(f"  wall {wall_s:.3f} s (stepping {stepping_s:.3f} s); {self.outcome}")
        print(f"  E0 = {self.e0_j:.5f} J above flat")
        rows = []
        for k, f in enumerate(MILESTONES):
            te = self.mat.exact_s[k]
            if self.hits[k] is None:
                print(f"  f = {f:.4f}: not reached")
                rows.append({"f": f, "t_s": None, "exact_s": te, "error_pct": None, "lost_pct": None})
                continue
            t, e = self.hits[k]
            err, lost = 100 * (t - te) / te, 100 * (self.e0_j - e) / self.e0_j
            print(f"  f = {f:.4f}: t {t:.4f} s, exact {te:.4f} s, error {err:+.3f} %, "
                  f"energy lost {lost:.3f} % of E0")
            rows.append({"f": f, "t_s": t, "exact_s": te, "error_pct": err, "lost_pct": lost})
        out = {"peer": self.name, "settings": settings, "links": links, "steps": steps,
               "sim_s": t_s, "wall_s": wall_s, "stepping_s": stepping_s,
               "outcome": self.outcome, "e0_j": self.e0_j, "milestones": rows}
        if max_gain_j is not None:
            out["max_gain_pct"] = 100 * max_gain_j / self.e0_j
        print(json.dumps(out))


def arguments(description: str, defaults: dict) -> argparse.ArgumentParser:
    """The flags every Python peer has; a peer adds its own."""
    p = argparse.ArgumentParser(description=description)
    p.add_argument("--scene", type=pathlib.Path, default=REPO / "scenes" / "yoga-mat.toml")
    p.add_argument("--dt-s", type=float, default=defaults["dt_s"], help="fixed time step (s)")
    p.add_argument("--links-per-turn", type=int, default=None,
                   help="links per turn (default: the scene's)")
    p.add_argument("--stop-fraction", type=float, default=0.9)
    p.add_argument("--max-wall-s", type=float, default=math.inf,
                   help="give up after this much wall time (s), reporting how far it got")
    p.add_argument("--trace", type=int, default=0,
                   help="print time, laid fraction and energy every this many steps")
    return p
