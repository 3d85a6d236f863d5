//! The exact chain against what is known without it: a free chain keeps its momentum and
//! angular momentum at any step, its joints rigid, and its energy to second order; a
//! pendulum's energy error is of second order in the step; the joints stay closed; joined
//! bodies moving as one lose nothing when their joint is made rigid; a rod landing flat on
//! one end leaves the other at 3V/2; on the floor a chain carries its weight, and slides to
//! rest under Coulomb's friction. Where a check was the nodal chain's (retired: its results
//! are in docs/history.md), its bound came with it and says so.

use super::*;

const TOLERANCE: Tolerance = Tolerance {
    position_m: 1e-12,
    max_iterations: 50,
    max_turn_rad: 0.3,
};

/// A straight chain of `n` links of length `l` and mass `m` along +x from the origin, each
/// a thin rod (inertia m l^2 / 12), at rest.
fn straight(n: usize, l: f64, m: f64) -> (Vec<Body>, Vec<Joint>) {
    let bodies = (0..n)
        .map(|k| Body {
            mass_kg: m,
            inertia_kg_m2: m * l * l / 12.0,
            position_m: [(k as f64 + 0.5) * l, 0.0],
            angle_rad: 0.0,
            velocity_m_s: [0.0, 0.0],
            spin_rad_s: 0.0,
        })
        .collect();
    let joints = (1..n)
        .map(|_| Joint {
            prev: [0.5 * l, 0.0],
            next: [-0.5 * l, 0.0],
        })
        .collect();
    (bodies, joints)
}

fn momentum(chain: &ExactChain) -> [f64; 3] {
    let mut p = [0.0; 3];
    for b in chain.bodies() {
        let [u, w] = b.velocity_m_s;
        let [x, y] = b.position_m;
        p[0] += b.mass_kg * u;
        p[1] += b.mass_kg * w;
        p[2] += b.mass_kg * (x * w - y * u) + b.inertia_kg_m2 * b.spin_rad_s;
    }
    p
}

/// A chain of 20 links bent in an arc, every link spinning at its own rate (30 rad/s on
/// average, 330 at most), each centre's velocity what the joints allow.
fn spinning_and_flexing() -> ExactChain {
    let (mut bodies, joints) = straight(20, 0.05, 0.01);
    // Each link's angle and spin from a bend, positions from the joints.
    let mut node = [0.0, 0.0];
    for (k, b) in bodies.iter_mut().enumerate() {
        let s = k as f64 / 20.0;
        b.angle_rad = 0.6 * (std::f64::consts::PI * s).sin();
        let half = rotate([0.025, 0.0], b.angle_rad);
        b.position_m = [node[0] + half[0], node[1] + half[1]];
        node = [node[0] + 2.0 * half[0], node[1] + 2.0 * half[1]];
    }
    // Rigid spin about the origin, plus each link's own flexing spin; the centres'
    // velocities follow from the joints, node by node.
    let mut node_v = [0.0, 0.0];
    for (k, b) in bodies.iter_mut().enumerate() {
        b.spin_rad_s = 30.0 + 300.0 * (k as f64 * 0.7).cos();
        let half = rotate([0.025, 0.0], b.angle_rad);
        b.velocity_m_s = [
            node_v[0] - b.spin_rad_s * half[1],
            node_v[1] + b.spin_rad_s * half[0],
        ];
        node_v = [
            node_v[0] - 2.0 * b.spin_rad_s * half[1],
            node_v[1] + 2.0 * b.spin_rad_s * half[0],
        ];
    }
    ExactChain::new(bodies, joints, None, TOLERANCE)
}

#[test]
fn a_free_chain_keeps_its_momentum_and_energy_and_its_angular_momentum_to_second_order() {
    let mut errors = Vec::new();
    for h in [1e-4, 5e-5, 2.5e-5, 1.25e-5] {
        let mut chain = spinning_and_flexing();
        let (p0, e0) = (momentum(&chain), chain.kinetic_j());
        let mut worst: [f64; 2] = [0.0; 2];
        let mut fastest: f64 = 0.0;
        for _ in 0..(0.2 / h) as usize {
            let report = chain.step(h, [0.0, 0.0]).expect("solves");
            assert!(report.converged, "{report:?}");
            let gap = chain.joint_gap_m();
            assert!(gap <= chain.position_tolerance_m(), "gap {gap:e}");
            let p = momentum(&chain);
            worst[0] = worst[0].max((p[2] - p0[2]).abs() / p0[2].abs());
            worst[1] = worst[1].max((chain.kinetic_j() / e0 - 1.0).abs());
            assert!((p[0] - p0[0]).abs() + (p[1] - p0[1]).abs() < 1e-12);
            let spin = chain.bodies().iter().map(|b| b.spin_rad_s.abs());
            fastest = fastest.max(spin.fold(0.0, f64::max));
        }
        println!(
            "h = {h:e} s (at most {:.3} rad a step): angular momentum {:.1e}, energy {:.1e}",
            fastest * h,
            worst[0],
            worst[1]
        );
        errors.push(worst);
    }
    // The joints' impulses meet at their anchors, so the angular momentum is kept to the
    // solve's rounding; the energy's error, the integrator's (RATTLE's), falls as the step
    // squared (measured: h^2.0 over the three halvings) and is within 1e-4 over the 0.2 s
    // from 0.04 rad a step on.
    for e in &errors {
        assert!(e[0] < 1e-12, "angular momentum drifted by {:e}", e[0]);
    }
    let (first, last) = (errors[0][1], errors[errors.len() - 1][1]);
    let order = (first / last).log2() / (errors.len() - 1) as f64;
    assert!(order > 1.8, "the energy error's order {order:.2}");
    assert!(errors[2][1] < 1e-4, "energy drifted by {:e}", errors[2][1]);
}

/// A chain of 8 links pinned at one end, released horizontal under gravity: returns the
/// largest error of its energy over 0.5 s, relative to the most kinetic energy it had.
fn pendulum_energy_error(h: f64) -> f64 {
    let (bodies, joints) = straight(8, 0.05, 0.01);
    let pin = Pin {
        anchor: [-0.025, 0.0],
        at_m: [0.0, 0.0],
    };
    let mut chain = ExactChain::new(bodies, joints, Some(pin), TOLERANCE);
    let g = 9.81;
    let energy = |c: &ExactChain| {
        c.kinetic_j()
            + c.bodies()
                .iter()
                .map(|b| b.mass_kg * g * b.position_m[1])
                .sum::<f64>()
    };
    let e0 = energy(&chain);
    let (mut worst, mut most) = (0.0_f64, 0.0_f64);
    for _ in 0..(0.5 / h).round() as usize {
        let report = chain.step(h, [0.0, -g]).expect("solves");
        assert!(report.converged && report.joint_gap_m < 1e-11, "{report:?}");
        worst = worst.max((energy(&chain) - e0).abs());
        most = most.max(chain.kinetic_j());
    }
    worst / most
}

/// A step whose drift turns a link too far is taken again as two halves; the attempt it
/// gave up leaves nothing behind, so the chain ends exactly where two half steps take it.
#[test]
fn a_step_too_long_for_the_drift_is_two_half_steps_exactly() {
    // The fastest link spins at 330 rad/s: 0.66 rad in 2 ms, more than the 0.3 allowed.
    let h = 2e-3;
    let mut whole = spinning_and_flexing();
    let report = whole.step(h, [0.0, -9.81]).expect("solves");
    assert!(report.pieces > 1, "{report:?}");
    let mut halves = spinning_and_flexing();
    for _ in 0..2 {
        halves.step(0.5 * h, [0.0, -9.81]).expect("solves");
    }
    assert_eq!(whole.bodies(), halves.bodies());
    assert!(whole.joint_gap_m() <= whole.position_tolerance_m());
}

#[test]
fn a_pinned_chain_s_energy_error_is_of_second_order_in_the_step() {
    let coarse = pendulum_energy_error(4e-4);
    let fine = pendulum_energy_error(2e-4);
    let order = (coarse / fine).log2();
    println!("energy error {coarse:.2e} at 4e-4 s, {fine:.2e} at 2e-4 s: order {order:.2}");
    assert!(coarse < 1e-2, "{coarse:e}");
    assert!((1.7..2.5).contains(&order), "order {order:.2}");
}

fn level_floor(friction: f64) -> Floor {
    Floor {
        point_m: [0.0, 0.0],
        normal: [0.0, 1.0],
        friction,
    }
}

/// Every node of a straight chain, each belonging to one link: the first link has both ends,
/// every other its far end.
fn nodes(n: usize, l: f64) -> Vec<Vec<[f64; 2]>> {
    (0..n)
        .map(|k| {
            if k == 0 {
                vec![[-0.5 * l, 0.0], [0.5 * l, 0.0]]
            } else {
                vec![[0.5 * l, 0.0]]
            }
        })
        .collect()
}

#[test]
fn a_chain_lying_on_the_floor_carries_its_weight_and_stays() {
    let (bodies, joints) = straight(10, 0.01, 0.001);
    let mut chain = ExactChain::new(bodies, joints, None, TOLERANCE);
    chain.set_floor(level_floor(0.5), &nodes(10, 0.01));
    let (h, g) = (1e-4, 9.81);
    for _ in 0..100 {
        let report = chain.step(h, [0.0, -g]).expect("solves");
        assert!(report.converged, "{report:?}");
        let up: f64 = chain.contacts().iter().map(|c| c.normal_n_s[1]).sum();
        let weight = 10.0 * 0.001 * g * h;
        assert!(
            (up / weight - 1.0).abs() < 1e-6,
            "{up:e} against {weight:e}"
        );
        // The floor does no work on it but the closing of the gap each step leaves, at most
        // the position tolerance: the weight times it, M g 1e-12 m (1e-13 J; measured at
        // most 1.4e-15 J a step).
        let most = 10.0 * 0.001 * g * TOLERANCE.position_m;
        for k in 0..2 {
            let work: f64 = chain.contacts().iter().map(|c| c.work_j[k]).sum();
            assert!(
                work.abs() <= most,
                "the floor's work {work:e} J (part {k}), expected 0 within {most:e} J"
            );
        }
    }
    for b in chain.bodies() {
        assert!(
            b.position_m[1].abs() < 1e-12 && b.velocity_m_s[1].abs() < 1e-9,
            "{b:?}"
        );
    }
    // At rest: the nodal chain's bound, 1e-20 J (measured 2e-40 J).
    let kinetic = chain.kinetic_j();
    assert!(
        kinetic < 1e-20,
        "kinetic {kinetic:e} J, expected 0 within 1e-20 J"
    );
}

#[test]
fn a_chain_sliding_on_the_floor_stops_as_coulomb_says() {
    // Ten links sliding at 0.5 m/s with friction 0.5: they decelerate at mu g and stop
    // after u / (mu g), their kinetic energy all taken by friction.
    let (mut bodies, joints) = straight(10, 0.01, 0.001);
    for b in &mut bodies {
        b.velocity_m_s = [0.5, 0.0];
    }
    let mut chain = ExactChain::new(bodies, joints, None, TOLERANCE);
    chain.set_floor(level_floor(0.5), &nodes(10, 0.01));
    let (h, g) = (1e-4, 9.81);
    let e0 = chain.kinetic_j();
    let (mut friction_w, mut t) = (0.0, 0.0);
    while chain.bodies()[0].velocity_m_s[0] > 1e-9 && t < 1.0 {
        let before: Vec<Body> = chain.bodies().to_vec();
        let report = chain.step(h, [0.0, -g]).expect("solves");
        assert!(report.converged, "{report:?}");
        for c in chain.contacts() {
            let (b0, b1) = (before[c.body], chain.bodies()[c.body]);
            let (u0, u1) = (b0.velocity_at(c.arm_m), b1.velocity_at(c.arm_m));
            friction_w += dot(
                c.friction_n_s,
                [0.5 * (u0[0] + u1[0]), 0.5 * (u0[1] + u1[1])],
            );
        }
        t += h;
    }
    let stop = 0.5 / (0.5 * g);
    assert!(
        (t - stop).abs() < 2.0 * h,
        "stopped at {t} s, Coulomb says {stop} s"
    );
    assert!(
        (friction_w / -e0 - 1.0).abs() < 1e-6,
        "friction took {friction_w:e} of {e0:e}"
    );
}

#[test]
fn a_long_chain_sliding_flat_on_a_frictionless_floor_keeps_its_speed_and_carries_its_weight() {
    // 2,000 links, each touching the floor at its middle and its far end (the first at its
    // near end too): 4,001 contact rows on 6,000 coordinates held by 3,998 joint rows, so
    // each link's points hold the same motion twice over. Sliding at 0.5 m/s with no
    // friction, the chain keeps its speed, stays on the floor and carries its weight, the
    // impulse shared among the points that hold the same motion. (Its cost, linear in the
    // links: benches/step.rs, exact_chain/on-floor.)
    let (n, l, m) = (2000, 0.01, 0.001);
    let (mut bodies, joints) = straight(n, l, m);
    for b in &mut bodies {
        b.velocity_m_s = [0.5, 0.0];
    }
    let mut chain = ExactChain::new(bodies, joints, None, TOLERANCE);
    let points: Vec<Vec<[f64; 2]>> = nodes(n, l)
        .into_iter()
        .map(|mut p| {
            p.push([0.0, 0.0]);
            p
        })
        .collect();
    chain.set_floor(level_floor(0.0), &points);
    let (h, g) = (1e-4, 9.81);
    for _ in 0..20 {
        let report = chain.step(h, [0.0, -g]).expect("solves");
        assert!(report.converged, "{report:?}");
        let up: f64 = chain.contacts().iter().map(|c| c.normal_n_s[1]).sum();
        let weight = n as f64 * m * g * h;
        assert!(
            (up / weight - 1.0).abs() < 1e-6,
            "{up:e} against {weight:e}"
        );
    }
    for b in chain.bodies() {
        assert!(
            b.position_m[1].abs() < 1e-12
                && b.velocity_m_s[1].abs() < 1e-9
                && (b.velocity_m_s[0] - 0.5).abs() < 1e-9,
            "{b:?}"
        );
    }
}

#[test]
fn a_body_touches_a_floor_only_at_its_hull_s_corners() {
    // A square with a point inside it and one on each of two edges; a point given twice.
    let square = [
        [0.0, 0.0],
        [1.0, 0.0],
        [0.5, 0.5],
        [1.0, 1.0],
        [0.5, 0.0],
        [0.0, 1.0],
        [0.0, 0.5],
        [1.0, 1.0],
    ];
    let corners = hull_corners(&square);
    let kept: Vec<usize> = (0..square.len()).filter(|&i| corners[i]).collect();
    assert_eq!(
        kept,
        [0, 1, 3, 5],
        "each corner once, nothing inside or on an edge"
    );
    // Points in a line: its two ends. One point, or two: themselves.
    let line: Vec<[f64; 2]> = (0..6).map(|i| [0.1 * f64::from(i), 0.2]).collect();
    assert_eq!(
        hull_corners(&line),
        [true, false, false, false, false, true]
    );
    assert_eq!(hull_corners(&[[1.0, 2.0]]), [true]);
    assert_eq!(hull_corners(&[[1.0, 2.0], [1.0, 2.0]]), [true, false]);
    // A curled piece: every point of a half turn's arc is a corner.
    let arc: Vec<[f64; 2]> = (0..9)
        .map(|i| {
            let a = std::f64::consts::PI * f64::from(i) / 8.0;
            [a.cos(), a.sin()]
        })
        .collect();
    assert!(hull_corners(&arc).iter().all(|&c| c));
}

/// The fastest spin of any body of `chain` (rad/s).
fn fastest_spin(chain: &ExactChain) -> f64 {
    chain
        .bodies()
        .iter()
        .map(|b| b.spin_rad_s.abs())
        .fold(0.0, f64::max)
}

/// The widest relative velocity of a joint's two anchors (the pin's anchor against the
/// world), and the fastest anchor's speed (m/s).
fn joint_slip_m_s(chain: &ExactChain) -> (f64, f64) {
    let (mut widest, mut fastest): (f64, f64) = (0.0, 0.0);
    let bodies = chain.bodies();
    for (i, j) in chain.joints().iter().enumerate() {
        let (a, b) = (bodies[i], bodies[i + 1]);
        let (va, vb) = (a.velocity_at(a.arm(j.prev)), b.velocity_at(b.arm(j.next)));
        widest = widest.max((va[0] - vb[0]).hypot(va[1] - vb[1]));
        fastest = fastest.max(va[0].hypot(va[1]));
    }
    if let (Some(pin), Some(first)) = (chain.pin(), bodies.first()) {
        let v = first.velocity_at(first.arm(pin.anchor));
        widest = widest.max(v[0].hypot(v[1]));
    }
    (widest, fastest)
}

#[test]
fn a_free_chain_keeps_its_momentum_angular_momentum_and_rigid_joints_at_any_step() {
    // The joints' impulses are equal and opposite and meet at their anchors, so the
    // momentum is kept (in gravity: it gains the weight's impulse, M g t) and the angular
    // momentum too, to the solve's rounding, whatever the step: here 0.02 to 0.6 rad a step
    // (the fastest body's turn, the step taken again at each step from its spin, as the
    // bang's rule does), 20,000 steps each, a step whose drift turns a body past 0.3 rad
    // taken in halves (the count is printed). Bounds: the nodal chain's, whose test this
    // was (momentum 1e-12, angular momentum 1e-9 of its start); measured here at most 2e-13
    // and 7e-10 (at 0.6 rad). The stage at each step's end holds every joint's anchors
    // together (`G v = 0`), so no stretching mode is left in the velocity (the nodal
    // chain's midpoint rule left one, of 3e-6 to 8e-3 of the energy from 0.1 to 0.3 rad a
    // step): the anchors' relative speed is rounding, measured at most 8e-16 of the fastest
    // anchor's speed, held to 1e-13. The energy is RATTLE's, not kept: printed (from 6e-5
    // of the kinetic energy at 0.02 rad a step to a growth of 1e2-1e3 times from 0.3 rad,
    // past the bang's 0.15 rad; its order in the step is checked above).
    for angle in [0.02, 0.1, 0.3, 0.6] {
        for g in [0.0, 9.81] {
            let mut chain = spinning_and_flexing();
            let mass: f64 = chain.bodies().iter().map(|b| b.mass_kg).sum();
            let potential = |c: &ExactChain| -> f64 {
                c.bodies()
                    .iter()
                    .map(|b| b.mass_kg * g * b.position_m[1])
                    .sum()
            };
            let (e0, k0, p0) = (
                chain.kinetic_j() + potential(&chain),
                chain.kinetic_j(),
                momentum(&chain),
            );
            let [mut worst_e, mut worst_l, mut worst_p, mut worst_slip] = [0.0_f64; 4];
            let (mut t, mut halved) = (0.0, 0);
            for _ in 0..20_000 {
                let h = angle / fastest_spin(&chain);
                t += h;
                let report = chain.step(h, [0.0, -g]).expect("solves");
                assert!(report.converged, "{report:?}");
                halved += usize::from(report.pieces > 1);
                let e = chain.kinetic_j() + potential(&chain);
                worst_e = worst_e.max((e - e0).abs() / k0);
                let p = momentum(&chain);
                let fall = -mass * g * t;
                let drift = (p[0] - p0[0]).abs().max((p[1] - p0[1] - fall).abs());
                worst_p = worst_p.max(drift / (p0[0].hypot(p0[1]) + fall.abs()));
                // In gravity the angular momentum about the origin changes: not checked.
                if g == 0.0 {
                    worst_l = worst_l.max((p[2] - p0[2]).abs() / p0[2].abs());
                }
                let (slip, fastest) = joint_slip_m_s(&chain);
                worst_slip = worst_slip.max(slip / fastest);
            }
            println!(
                "{angle} rad a step, g = {g}: momentum {worst_p:.1e} (bound 1e-12), angular \
                 momentum {worst_l:.1e} (bound 1e-9), joints' slip {worst_slip:.1e} (bound \
                 1e-13); energy {worst_e:.1e}; {halved} steps halved"
            );
            assert!(
                worst_p < 1e-12,
                "momentum drifted by {worst_p:e} at {angle} rad, g = {g}; expected < 1e-12"
            );
            assert!(
                worst_l < 1e-9,
                "angular momentum drifted by {worst_l:e} at {angle} rad; expected < 1e-9"
            );
            assert!(
                worst_slip < 1e-13,
                "a joint's anchors slipped at {worst_slip:e} of the fastest anchor's speed at \
                 {angle} rad, g = {g}; expected < 1e-13"
            );
            assert!(chain.joint_gap_m() <= chain.position_tolerance_m());
        }
    }
}

#[test]
fn a_rod_landing_flat_on_one_end_leaves_the_other_at_three_halves_its_speed() {
    // A thin uniform rod falling flat at V whose one end lands plastically and sticks: its
    // angular momentum about that end is kept, m V l / 2 = (m l^2 / 3) omega, so the other
    // end moves at omega l = 3 V / 2 (Grewal, Johnson and Ruina, Am. J. Phys. 79, 723,
    // 2011), and the impact takes m V^2 / 2 - (m l^2 / 3) omega^2 / 2 = m V^2 / 8. No
    // gravity: the impact alone, in one step, the rod touching the floor at its landing end
    // only, 1 nm above it. Bound 1e-3 of each (the nodal chain's, whose test this was);
    // measured within 1e-8 of 3 V / 2 and 5e-8 of m V^2 / 8.
    let (l, m) = (0.1, 0.05);
    for (v, h) in [(1.0, 1e-4), (2.0, 1e-5), (0.3, 1e-3)] {
        let rod = Body {
            mass_kg: m,
            inertia_kg_m2: m * l * l / 12.0,
            position_m: [0.5 * l, 1e-9],
            angle_rad: 0.0,
            velocity_m_s: [0.0, -v],
            spin_rad_s: 0.0,
        };
        let mut chain = ExactChain::new(vec![rod], Vec::new(), None, TOLERANCE);
        chain.set_floor(level_floor(1.0), &[vec![[-0.5 * l, 0.0]]]);
        let report = chain.step(h, [0.0, 0.0]).expect("solves");
        assert!(report.converged, "{report:?}");
        let b = chain.bodies()[0];
        let far = b.velocity_at(b.arm([0.5 * l, 0.0]));
        let speed = far[0].hypot(far[1]);
        let lost: f64 = -chain
            .contacts()
            .iter()
            .map(|c| c.work_j[0] + c.work_j[1])
            .sum::<f64>();
        let want = m * v * v / 8.0;
        println!(
            "V = {v} m/s, h = {h} s: the far end at {:.9} V (3/2 expected), the floor took \
             {:.9} of m V^2 / 8",
            speed / v,
            lost / want
        );
        assert!(
            (speed / (1.5 * v) - 1.0).abs() < 1e-3,
            "the far end at {speed} m/s, expected 3 V / 2 = {} m/s",
            1.5 * v
        );
        assert!(
            (lost / want - 1.0).abs() < 1e-3,
            "the floor took {lost:e} J, expected m V^2 / 8 = {want:e} J"
        );
    }
}

#[test]
fn joined_bodies_moving_as_one_lose_nothing_when_their_joint_is_made_rigid() {
    // Two bodies with their centres off their joint's line, joined, the second's velocity
    // what the first's gives the joint: the joint has no relative motion to take, so making
    // it rigid at the first step takes nothing (`caught_j`, bound 1e-15 J of the 0.28 J,
    // the nodal chain's round trip's; measured 0).
    let ends = [
        [[-0.02, 0.003], [0.03, -0.001]],
        [[-0.01, 0.0], [0.02, 0.004]],
    ];
    let first = Body {
        mass_kg: 0.3,
        inertia_kg_m2: 2e-5,
        position_m: [0.1, 0.2],
        angle_rad: 0.4,
        velocity_m_s: [1.0, -0.5],
        spin_rad_s: 7.0,
    };
    let joint = first.point(ends[0][1]);
    let joint_v = first.velocity_at(first.arm(ends[0][1]));
    let mut second = Body {
        mass_kg: 0.2,
        inertia_kg_m2: 1e-5,
        position_m: [0.0, 0.0],
        angle_rad: -1.1,
        velocity_m_s: [0.0, 0.0],
        spin_rad_s: -3.0,
    };
    let arm = second.arm(ends[1][0]);
    second.position_m = [joint[0] - arm[0], joint[1] - arm[1]];
    second.velocity_m_s = [
        joint_v[0] + second.spin_rad_s * arm[1],
        joint_v[1] - second.spin_rad_s * arm[0],
    ];
    let joints = vec![Joint {
        prev: ends[0][1],
        next: ends[1][0],
    }];
    let mut chain = ExactChain::new(vec![first, second], joints, None, TOLERANCE);
    let report = chain.step(1e-6, [0.0, 0.0]).expect("solves");
    assert!(
        report.caught_j.abs() < 1e-15,
        "making the joint rigid took {:e} J, expected 0",
        report.caught_j
    );
}

mod layers;

mod bounded;
