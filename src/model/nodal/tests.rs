//! The nodal chain against what is known without it: a free chain keeps its energy, its
//! momentum and its angular momentum at any step; a rigid body's round trip; a rod landing
//! flat on one end; a chain resting on the floor carries its weight.

use super::*;

const TOLERANCE: Tolerance = Tolerance {
    position_m: 1e-12,
    max_iterations: 50,
    max_turn_rad: 1.2,
};

/// A thin uniform rod of length `l` and mass `m` as a piece.
fn rod(l: f64, m: f64) -> Piece {
    Piece {
        mass_kg: m,
        centre: [0.5, 0.0],
        gyration: 1.0 / 3.0,
        length_m: l,
        chord_angle_rad: 0.0,
    }
}

/// 20 rods of 5 cm and 10 g bent in an arc, each turning at its own rate (30 rad/s on
/// average, 330 at most), the first node moving at 0.3 m/s: velocities the rods' rigidity
/// allows.
fn flexing() -> NodalChain {
    let (n, l) = (20, 0.05);
    let mut nodes = vec![[0.0, 0.0]];
    let mut velocities = vec![[0.3, -0.2]];
    for k in 0..n {
        let s = k as f64 / n as f64;
        let angle = 0.6 * (std::f64::consts::PI * s).sin() + 0.1;
        let d = [l * angle.cos(), l * angle.sin()];
        let spin = 30.0 + 300.0 * (k as f64 * 0.7).cos();
        let (x, v) = (nodes[k], velocities[k]);
        nodes.push(add(x, d));
        velocities.push(add(v, scale(spin, quarter(d))));
    }
    NodalChain::new(nodes, velocities, vec![rod(l, 0.01); n], false, TOLERANCE)
}

fn fastest_spin(chain: &NodalChain) -> f64 {
    (0..chain.pieces().len())
        .map(|i| chain.body(i).spin_rad_s.abs())
        .fold(0.0, f64::max)
}

#[test]
fn a_free_chain_keeps_its_energy_momentum_and_angular_momentum_at_any_step() {
    // The midpoint rule with the rigidity's gradient at the midpoint: the constraints do no
    // work and their impulses are central, so energy and angular momentum are kept to the
    // Newton tolerance (the pieces' lengths within 1e-12 m, 2e-11 of a piece), whatever the
    // step: here 0.02 to 0.6 rad a step (the fastest piece's turn: the step is taken again
    // at each step from its spin, as the bang's rule does), 20,000 steps each. Where
    // Newton's method does not converge from its first iterate (from about 0.4 rad a step,
    // on steps where a piece spins up within the step), the step is taken in halves, each
    // as exact: the count is printed.
    for angle in [0.02, 0.1, 0.3, 0.6] {
        for g in [0.0, 9.81] {
            let mut chain = flexing();
            let gravity = [0.0, -g];
            let e0 = chain.kinetic_j() + chain.potential_j(gravity);
            let scale_j = chain.kinetic_j();
            let p0 = chain.momentum();
            let (mut worst_e, mut worst_l, mut worst_p): (f64, f64, f64) = (0.0, 0.0, 0.0);
            // In gravity the angular momentum about the origin changes: not checked.
            let (mut t, mut halved) = (0.0, 0);
            for _ in 0..20_000 {
                let h = angle / fastest_spin(&chain);
                t += h;
                let report = chain.step(h, gravity).expect("solves");
                assert!(report.converged, "{report:?}");
                halved += usize::from(report.pieces > 1);
                let e = chain.kinetic_j() + chain.potential_j(gravity);
                worst_e = worst_e.max((e - e0).abs() / scale_j);
                let p = chain.momentum();
                let fall = chain_mass(&chain) * gravity[1] * t;
                let drift = (p[0] - p0[0]).abs().max((p[1] - p0[1] - fall).abs());
                worst_p = worst_p.max(drift / (p0[0].hypot(p0[1]) + fall.abs()));
                if g == 0.0 {
                    worst_l = worst_l.max((p[2] - p0[2]).abs() / p0[2].abs());
                }
            }
            println!(
                "{angle} rad a step, g = {g}: energy {worst_e:.1e}, angular momentum \
                 {worst_l:.1e}, momentum {worst_p:.1e}; {halved} steps halved"
            );
            assert!(
                worst_e < 1e-9,
                "energy drifted by {worst_e:e} at {angle} rad, g = {g}"
            );
            assert!(
                worst_l < 1e-9,
                "angular momentum drifted by {worst_l:e} at {angle} rad"
            );
            assert!(
                worst_p < 1e-12,
                "momentum drifted by {worst_p:e} at {angle} rad, g = {g}"
            );
            assert!(chain.length_error_m() <= chain.position_tolerance_m());
        }
    }
}

fn chain_mass(chain: &NodalChain) -> f64 {
    chain.pieces().iter().map(|p| p.mass_kg).sum()
}

#[test]
fn bodies_come_back_as_they_went_in() {
    // Two bodies with their centres off their chords, joined: the chain's bodies are the
    // same poses and (rigid, joined) velocities.
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
    second.position_m = sub(joint, arm);
    second.velocity_m_s = sub(joint_v, scale(second.spin_rad_s, quarter(arm)));
    let bodies = [first, second];
    let (chain, lost) = NodalChain::of_bodies(&bodies, &ends, false, TOLERANCE).expect("solves");
    assert!(lost.abs() < 1e-15, "lost {lost:e} J");
    for (i, want) in bodies.iter().enumerate() {
        let got = chain.body(i);
        let close = |a: f64, b: f64| (a - b).abs() < 1e-12;
        assert!(close(got.mass_kg, want.mass_kg) && close(got.inertia_kg_m2, want.inertia_kg_m2));
        for k in 0..2 {
            assert!(
                close(got.position_m[k], want.position_m[k]),
                "{got:?} against {want:?}"
            );
            assert!(
                close(got.velocity_m_s[k], want.velocity_m_s[k]),
                "{got:?} against {want:?}"
            );
        }
        assert!(
            close(got.spin_rad_s, want.spin_rad_s),
            "{got:?} against {want:?}"
        );
        let turn = (got.angle_rad - want.angle_rad).sin();
        assert!(turn.abs() < 1e-12, "{got:?} against {want:?}");
    }
}

fn floor(friction: f64) -> Floor {
    Floor {
        point_m: [0.0, 0.0],
        normal: [0.0, 1.0],
        friction,
    }
}

#[test]
fn a_rod_landing_flat_on_one_end_leaves_the_other_at_three_halves_its_speed() {
    // A thin uniform rod falling flat at V whose one end lands plastically and sticks: its
    // angular momentum about that end is kept, m V l / 2 = (m l^2 / 3) omega, so the other
    // end moves at omega l = 3 V / 2 (Grewal, Johnson and Ruina, Am. J. Phys. 79, 723,
    // 2011). No gravity: the impact alone.
    for (v, h) in [(1.0, 1e-4), (2.0, 1e-5), (0.3, 1e-3)] {
        let l = 0.1;
        let nodes = vec![[0.0, 1e-9], [l, 1e-9]];
        let velocities = vec![[0.0, -v], [0.0, -v]];
        let mut chain = NodalChain::new(nodes, velocities, vec![rod(l, 0.05)], false, TOLERANCE);
        chain.set_floor(floor(1.0), &[vec![[0.0, 0.0]]]);
        let report = chain.step(h, [0.0, 0.0]).expect("solves");
        assert!(report.converged, "{report:?}");
        let far = chain.velocities()[1];
        let speed = far[0].hypot(far[1]);
        println!("V = {v} m/s, h = {h} s: the far end at {:.6} V", speed / v);
        assert!(
            (speed / (1.5 * v) - 1.0).abs() < 1e-3,
            "{speed} m/s against {}",
            1.5 * v
        );
        // The impact's loss: half the kinetic energy's share in the landing end's motion,
        // m V^2 / 2 - (m l^2 / 3) omega^2 / 2 = m V^2 / 8.
        let lost = -report.floor_work_j[0] - report.floor_work_j[1];
        let want = 0.05 * v * v / 8.0;
        assert!(
            (lost / want - 1.0).abs() < 1e-3,
            "lost {lost:e} J against {want:e}"
        );
    }
}

#[test]
fn a_chain_lying_on_the_floor_carries_its_weight_and_stays() {
    let (n, l, m) = (12, 0.01, 0.002);
    let nodes: Vec<[f64; 2]> = (0..=n).map(|k| [k as f64 * l, 0.0]).collect();
    let mut chain = NodalChain::new(
        nodes,
        vec![[0.0; 2]; n + 1],
        vec![rod(l, m); n],
        false,
        TOLERANCE,
    );
    let points: Vec<Vec<[f64; 2]>> = (0..n)
        .map(|i| {
            if i == 0 {
                vec![[0.0, 0.0], [1.0, 0.0]]
            } else {
                vec![[1.0, 0.0]]
            }
        })
        .collect();
    chain.set_floor(floor(0.5), &points);
    let h = 1e-3;
    for _ in 0..200 {
        let report = chain.step(h, [0.0, -9.81]).expect("solves");
        assert!(report.converged, "{report:?}");
        let up: f64 = chain.contacts().iter().map(|c| c.normal_n_s[1]).sum();
        let weight = n as f64 * m * 9.81 * h;
        // Within the contacts' regularisation (1e-9 of their inverse mass).
        assert!(
            (up / weight - 1.0).abs() < 1e-6,
            "{up:e} N s against {weight:e}"
        );
        // The floor does no work on it but its compliance's: each contact row falls short
        // of its target by 1e-9 of its inverse mass times its impulse, taking at most
        // 2e-9 P^2 / m a contact, 2e-9 M (g h)^2 in all.
        let work = report.floor_work_j;
        let most = 4e-9 * n as f64 * m * (9.81 * h).powi(2);
        assert!(
            work[0] <= 0.0 && -work[0] < most && work[1].abs() < most,
            "{work:?}"
        );
    }
    assert!(chain.kinetic_j() < 1e-20, "{} J", chain.kinetic_j());
    // It sinks by its compliance alone, far less than the slop the projection allows.
    let deepest = chain.nodes().iter().map(|x| -x[1]).fold(0.0, f64::max);
    assert!(deepest < 1e-10, "sank {deepest:e} m");
}

/// The kinetic energy of the pieces as rigid bodies (each its centre's velocity and the
/// chord's spin): what is left of the chain's own is in its nodes' velocities along the
/// chords, which a rigid piece cannot have (J).
fn rigid_kinetic_j(chain: &NodalChain) -> f64 {
    (0..chain.pieces().len())
        .map(|i| chain.body(i).kinetic_j())
        .sum()
}

#[test]
fn the_end_velocities_stretch_the_pieces_by_a_share_that_grows_with_the_step() {
    // The midpoint rule holds each piece's length at both ends of a step and its chord's
    // mean stretching rate at zero; nothing holds the end's rate, which flips its sign
    // from step to step and is driven by the pieces' changing spins. Its kinetic energy,
    // the chain's less its pieces' as rigid bodies, is the measure; the step's energy
    // stays exact. Measured (mean over 4000 steps of the flexing chain): 4e-10 of the
    // energy at 0.02 rad a step, 2e-8 at 0.05, 3e-6 at 0.1, 3e-4 at 0.2, 8e-3 at 0.3.
    let mut shares = Vec::new();
    for angle in [0.02, 0.05, 0.1, 0.3] {
        let mut chain = flexing();
        let e0 = chain.kinetic_j();
        let mut mean = 0.0;
        for _ in 0..4000 {
            let h = angle / fastest_spin(&chain);
            chain.step(h, [0.0, 0.0]).expect("solves");
            mean += (chain.kinetic_j() - rigid_kinetic_j(&chain)) / e0 / 4000.0;
        }
        println!("{angle} rad a step: the pieces' stretching holds {mean:.1e} of the energy");
        shares.push(mean);
    }
    assert!(shares[1] < 1e-7, "at 0.05 rad a step: {:e}", shares[1]);
    assert!(shares.windows(2).all(|w| w[1] > w[0]), "{shares:?}");
}

#[test]
fn a_chain_landing_on_the_floor_never_gains_energy_and_books_every_joule() {
    // 60 pieces of 0.5 mm, pinned 0.5 mm above the floor, thrown down and sideways in a
    // wave, land on a floor with friction 1 at 0.1 rad a step: the floor's work, as the
    // step books it, is the whole change of energy but for the Newton tolerance; the energy
    // never rises; what is left in the pieces' stretching is printed.
    let (n, l, m) = (60, 0.0005, 3.5e-6);
    let mut nodes = vec![[0.0, 0.0005]];
    let mut velocities = vec![[0.0, 0.0]];
    for k in 0..n {
        let a = 0.3 * (k as f64 * 0.37).sin();
        nodes.push(add(nodes[k], [l * a.cos(), l * a.sin()]));
        velocities.push([3.0 * (k as f64 * 0.2).cos(), -2.0 + (k as f64 * 0.5).sin()]);
    }
    let tolerance = Tolerance {
        position_m: 1e-9 * l,
        max_iterations: 50,
        max_turn_rad: 0.2,
    };
    // The velocities made rigid first, as a chain of bodies hands them over.
    let thrown = NodalChain::new(nodes, velocities, vec![rod(l, m); n], true, tolerance);
    let bodies: Vec<Body> = (0..n).map(|i| thrown.body(i)).collect();
    let ends: Vec<[[f64; 2]; 2]> = bodies
        .iter()
        .enumerate()
        .map(|(i, b)| {
            let back = |p: [f64; 2]| {
                let (s, c) = (-b.angle_rad).sin_cos();
                let r = sub(p, b.position_m);
                [c * r[0] - s * r[1], s * r[0] + c * r[1]]
            };
            [back(thrown.nodes()[i]), back(thrown.nodes()[i + 1])]
        })
        .collect();
    let (mut chain, _) = NodalChain::of_bodies(&bodies, &ends, true, tolerance).expect("made");
    chain.set_floor(floor(1.0), &vec![vec![[1.0, 0.0]]; n]);
    let g = [0.0, -9.81];
    let e0 = chain.kinetic_j() + chain.potential_j(g);
    let (mut t, mut booked, mut highest) = (0.0, 0.0, f64::NEG_INFINITY);
    while t < 0.3 {
        let spin = (0..n)
            .map(|i| chain.body(i).spin_rad_s.abs())
            .fold(0.0, f64::max);
        let h = (0.1 / spin).min(1e-4);
        let r = chain.step(h, g).expect("solves");
        t += h;
        booked += r.floor_work_j[0] + r.floor_work_j[1] + r.joint_work_j + r.projection_j;
        let e = chain.kinetic_j() + chain.potential_j(g);
        highest = highest.max(e - e0);
    }
    let e = chain.kinetic_j() + chain.potential_j(g);
    let stretching = chain.kinetic_j() - rigid_kinetic_j(&chain);
    println!(
        "after 0.3 s: {:.3e} J of {:.3e} J taken, booked {booked:.3e} J; kinetic {:.2e} J, \
         {stretching:.2e} J of it in the pieces' stretching",
        e0 - e,
        e0,
        chain.kinetic_j()
    );
    assert!(
        highest <= 1e-12 * e0.abs(),
        "the energy rose by {highest:e} J"
    );
    assert!(
        (e - e0 - booked).abs() < 1e-9 * (e0 - e),
        "{:e} J unbooked",
        e - e0 - booked
    );
}
