#!/usr/bin/env python3
"""The yoga mat in pymunk (Chipmunk2D), as a careful user would write it: a chain of segment
shapes (radius b/2) joined by PivotJoints on a static floor segment, friction 1, one fixed
time step. A chain of free pivots does not stay wound, so each pivot also has a
RotaryLimitJoint holding its spiral angle until its node reaches the floor, where the tape
peels off the coil, and is removed there. Links touch only the floor. A peer for
docs/peers.md; the last line printed is one JSON object for tools/peers/compare.py.
"""

from __future__ import annotations

import math
import pathlib
import sys
import time

started = time.perf_counter()
sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))

import numpy as np  # noqa: E402
import pymunk  # noqa: E402

from common import LaidMeter, Mat, Recorder, arguments  # noqa: E402


def main() -> None:
    p = arguments(__doc__.splitlines()[0], {"dt_s": 1e-4})
    p.add_argument("--iterations", type=int, default=10, help="solver iterations (pymunk's 10)")
    p.add_argument("--slop-m", type=float, default=None,
                   help="collision slop (m; default b / 100: pymunk's 0.1 is meant for pixels)")
    p.add_argument("--release-m", type=float, default=None,
                   help="a lock is removed once its node is this close to the laid midline "
                        "height (m; default b / 100)")
    p.add_argument("--error-bias", type=float, default=None,
                   help="joints' error left unfixed after a second (pymunk's 0.9^60 = 0.0018 "
                        "lets the locked coil sag)")
    args = p.parse_args()
    mat = Mat(args.scene, args.links_per_turn)
    psis, nodes, rot0, contact, omega = mat.nodes()
    b, g = mat.thickness_m, mat.g_m_s2
    release_m = args.release_m if args.release_m is not None else 0.01 * b

    space = pymunk.Space()
    space.gravity = (0.0, -g)
    space.iterations = args.iterations
    space.collision_slop = args.slop_m if args.slop_m is not None else 0.01 * b
    floor = pymunk.Segment(space.static_body, (-10.0, 0.0), (10.0, 0.0), 0.0)
    floor.friction = mat.friction
    space.add(floor)

    chords = np.diff(nodes, axis=0)
    lengths = np.hypot(chords[:, 0], chords[:, 1])
    angles = np.arctan2(chords[:, 1], chords[:, 0])
    masses = mat.mass_kg * lengths / lengths.sum()
    tape = pymunk.ShapeFilter(group=1)
    bodies, locks = [], []
    for k in range(len(chords)):
        # The exact model's tape is a line mass on the midline: mass by length, a rod's inertia.
        body = pymunk.Body(masses[k], masses[k] * lengths[k] ** 2 / 12)
        centre = nodes[k] + 0.5 * chords[k]
        body.position = tuple(centre)
        body.angle = float(angles[k])
        rel = centre - contact
        body.velocity = (-omega * rel[1], omega * rel[0])
        body.angular_velocity = omega
        seg = pymunk.Segment(body, (-0.5 * lengths[k], 0.0), (0.5 * lengths[k], 0.0), 0.5 * b)
        seg.friction = mat.friction
        seg.filter = tape
        space.add(body, seg)
        if bodies:
            prev = bodies[-1]
            pivot = pymunk.PivotJoint(prev, body, tuple(nodes[k]))
            pivot.collide_bodies = False
            rest = float(angles[k] - angles[k - 1])
            lock = pymunk.RotaryLimitJoint(prev, body, rest, rest)
            if args.error_bias is not None:
                pivot.error_bias = lock.error_bias = args.error_bias
            space.add(pivot, lock)
            locks.append(lock)
        bodies.append(body)

    def energy() -> float:
        total = 0.0
        for body, m in zip(bodies, masses):
            v = body.velocity
            total += 0.5 * m * (v.x * v.x + v.y * v.y) + 0.5 * body.moment * body.angular_velocity ** 2
            total += m * g * (body.position.y - 0.5 * b)
        return total

    def angle_of(lo: int, hi: int) -> np.ndarray:
        return np.array([bodies[j].angle for j in range(lo, hi)])

    e0 = energy()
    meter = LaidMeter(mat, angles - rot0)
    rec = Recorder("pymunk", mat, e0, args.stop_fraction, args.max_wall_s)
    next_lock, t, steps, stepping_s = 0, 0.0, 0, 0.0
    while True:
        tick = time.perf_counter()
        space.step(args.dt_s)
        stepping_s += time.perf_counter() - tick
        steps += 1
        t = steps * args.dt_s
        # Free the joints whose node has reached the floor: the tape peels off there.
        while next_lock < len(locks):
            body = bodies[next_lock]
            node_y = body.local_to_world((0.5 * lengths[next_lock], 0.0)).y
            if node_y > 0.5 * b + release_m:
                break
            space.remove(locks[next_lock])
            next_lock += 1
        f = meter(angle_of)
        if args.trace and steps % args.trace == 0:
            print(f"t {t:.4f} f {f:.5f} E {energy():.5f} locks freed {next_lock}", file=sys.stderr)
        if rec.observe(t, args.dt_s, f, energy):
            break
    settings = {"dt_s": args.dt_s, "iterations": args.iterations,
                "slop_m": space.collision_slop, "release_m": release_m, "error_bias": args.error_bias,
                "links_per_turn": mat.links_per_turn}
    rec.report(started, stepping_s, steps, t, settings, len(bodies))


if __name__ == "__main__":
    main()
