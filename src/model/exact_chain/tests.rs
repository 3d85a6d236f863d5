//! The exact chain against what is known without it: a free chain keeps its momentum and
//! energy, and its angular momentum to second order; a pendulum's energy error is of second
//! order in the step; the joints stay closed; on the floor a chain carries its weight, and
//! slides to rest under Coulomb's friction.

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
    }
    for b in chain.bodies() {
        assert!(
            b.position_m[1].abs() < 1e-12 && b.velocity_m_s[1].abs() < 1e-9,
            "{b:?}"
        );
    }
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
