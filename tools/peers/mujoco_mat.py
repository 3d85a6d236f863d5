#!/usr/bin/env python3
"""The yoga mat in MuJoCo, as a careful user would write it: a planar chain of capsules
(radius b/2) on a plane, the root free in the plane (slide x, slide z, hinge y) and every
other link hinged to the one before, friction 1, one fixed time step. A chain of free
hinges does not stay wound, so each hinge is held at its spiral angle by an equality
constraint until its node reaches the floor, where the tape peels off the coil, and is
free from then on. Links touch only the floor. A peer for docs/peers.md; the last line
printed is one JSON object for tools/peers/compare.py.
"""

from __future__ import annotations

import pathlib
import sys
import time

started = time.perf_counter()
sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))

import mujoco  # noqa: E402
import numpy as np  # noqa: E402

from common import LaidMeter, Mat, Recorder, arguments  # noqa: E402


def model_xml(mat: Mat, nodes: np.ndarray, args) -> str:
    """Every body frame starts unrotated at its link's near node; the capsule runs to the far
    node. MuJoCo's plane is x-z, gravity along -z; a hinge about +y turns x towards -z."""
    b = mat.thickness_m
    radius_m = 0.5 * (args.collider_thickness_m or b)
    chords = np.diff(nodes, axis=0)
    lengths = np.hypot(chords[:, 0], chords[:, 1])
    masses = mat.mass_kg * lengths / lengths.sum()
    n = len(chords)
    solref = f'solref="{args.solref_s} 1" solimp="{args.solimp}"'
    out = [
        '<mujoco model="yoga-mat">',
        f'<option timestep="{args.dt_s}" gravity="0 0 {-mat.g_m_s2}" integrator="{args.integrator}"'
        f' cone="{args.cone}" iterations="{args.iterations}"/>',
        # Links meet the floor (contype 1, conaffinity 2) and not each other (contype 2,
        # conaffinity 1).
        f'<default><geom friction="{mat.friction} 0.005 0.0001" {solref}'
        ' contype="2" conaffinity="1"/><equality ' + solref + "/></default>",
                # The plane sits a capsule radius below the laid midline (b/2).
        f'<worldbody><geom name="floor" type="plane" size="5 1 0.1" pos="0 0 {0.5 * b - radius_m}"'
        ' contype="1" conaffinity="2"/>',
    ]
    close = []
    for k in range(n):
        dx, dz = chords[k]
        at = nodes[0] if k == 0 else chords[k - 1]
        out.append(f'<body name="l{k}" pos="{at[0]:.17g} 0 {at[1]:.17g}">')
        if k == 0:
            out.append('<joint type="slide" axis="1 0 0"/><joint type="slide" axis="0 0 1"/>')
        out.append(f'<joint name="h{k}" type="hinge" axis="0 1 0"/>')
        # The exact model's tape is a line mass on the midline: mass by length, a rod's
        # inertia about y (the other two only need to be valid).
        inertia = masses[k] * lengths[k] ** 2 / 12
        out.append(
            f'<inertial pos="{dx / 2:.17g} 0 {dz / 2:.17g}" mass="{masses[k]:.17g}"'
            f' diaginertia="{inertia:.17g} {inertia:.17g} {inertia:.17g}"/>'
        )
        out.append(
            f'<geom type="capsule" size="{radius_m}" mass="0"'
            f' fromto="0 0 0 {dx:.17g} 0 {dz:.17g}"/>'
        )
        close.append("</body>")
    out += close[::-1] + ["</worldbody><equality>"]
    # Hinge k (k >= 1) joins links k - 1 and k at node k; its angle is 0 on the spiral.
    out += [f'<joint joint1="h{k}"/>' for k in range(1, n)]
    out.append("</equality></mujoco>")
    return "\n".join(out)


def main() -> None:
    p = arguments(__doc__.splitlines()[0], {"dt_s": 1e-4})
    p.add_argument("--iterations", type=int, default=100, help="constraint solver iterations")
    p.add_argument("--solref-s", type=float, default=2e-4,
                   help="time constant of contacts and locks (s; MuJoCo's default is 0.02)")
    p.add_argument("--solimp", default="0.9999 0.9999 0.001",
                   help="constraint impedance, dmin dmax width (MuJoCo's default 0.9 0.95 0.001 "
                        "lets a twentieth of every load through the locks, and the coil sags)")
    p.add_argument("--collider-thickness-m", type=float, default=None,
                   help="capsule diameter (m; default b); the plane is put half of it below "
                        "the laid midline, so a thin capsule rolls the coil on its midline")
    p.add_argument("--integrator", default="implicitfast")
    p.add_argument("--release-m", type=float, default=None,
                   help="a hinge is freed once its node is this close to the laid midline "
                        "height (m; default b / 100)")
    p.add_argument("--cone", default="pyramidal")
    args = p.parse_args()
    mat = Mat(args.scene, args.links_per_turn)
    psis, nodes, rot0, contact, omega = mat.nodes()
    model = mujoco.MjModel.from_xml_string(model_xml(mat, nodes, args))
    data = mujoco.MjData(model)
    # Rolling about the contact, which is the root's origin (node 0): the root's slides
    # start at rest and its hinge turns at -omega (a hinge about +y is clockwise in x-z).
    data.qvel[2] = -omega
    mujoco.mj_forward(model, data)
    b, g, n = mat.thickness_m, mat.g_m_s2, model.nbody - 1
    masses = model.body_mass[1:].copy()
    chords = np.diff(nodes, axis=0)
    frame_angles = np.arctan2(chords[:, 1], chords[:, 0]) - rot0

    def energy() -> float:
        mujoco.mj_forward(model, data)
        kinetic = 0.5 * float(data.qvel @ _mass_times(model, data))
        heights = data.xipos[1:, 2]
        return kinetic + float(masses @ (heights - 0.5 * b)) * g

    def angle_of(lo: int, hi: int) -> np.ndarray:
        # Body k's frame has turned by beta about y, which takes x to (cos, -sin beta) in x-z:
        # its chord's world angle is its start angle less beta.
        m = data.xmat[1 + lo : 1 + hi]
        turn = np.arctan2(m[:, 6], m[:, 0])
        return frame_angles[lo:hi] + rot0 + turn

    release_m = args.release_m if args.release_m is not None else 0.01 * b
    next_lock = 0
    e0 = energy()
    meter = LaidMeter(mat, frame_angles)
    rec = Recorder("mujoco", mat, e0, args.stop_fraction, args.max_wall_s)
    t, steps, stepping_s = 0.0, 0, 0.0
    while True:
        tick = time.perf_counter()
        mujoco.mj_step(model, data)
        stepping_s += time.perf_counter() - tick
        steps += 1
        # mj_step leaves the positions of the step's start in xmat: they are one step old.
        t = data.time - args.dt_s
        # Free the hinges whose node has reached the floor: the tape peels off there. Body
        # k's origin is node k, where hinge k and equality k - 1 are.
        while next_lock < model.neq and data.xpos[next_lock + 2, 2] <= 0.5 * b + release_m:
            data.eq_active[next_lock] = 0
            next_lock += 1
        f = meter(angle_of)
        if args.trace and steps % args.trace == 0:
            print(f"t {t:.4f} f {f:.5f} E {energy():.5f} hinges freed {next_lock}", file=sys.stderr)
        if rec.observe(t, args.dt_s, f, energy):
            break
    settings = {"dt_s": args.dt_s, "iterations": args.iterations, "solref_s": args.solref_s,
                "solimp": args.solimp, "collider_thickness_m": 2 * float(model.geom_size[1, 0]), "integrator": args.integrator, "cone": args.cone, "release_m": release_m,
                "links_per_turn": mat.links_per_turn}
    rec.report(started, stepping_s, steps, t, settings, n)


def _mass_times(model, data) -> np.ndarray:
    out = np.zeros(model.nv)
    mujoco.mj_mulM(model, data, out, data.qvel)
    return out


if __name__ == "__main__":
    main()
