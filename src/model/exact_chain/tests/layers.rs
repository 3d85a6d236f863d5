//! The tape's layers against what is known without them: a rod landing on one end on the
//! laid tape, a thickness above it, leaves the other end at 3V/2 as on the floor; two
//! pieces closing like scissors meet at their tips, keep their momentum and angular
//! momentum, and lose what a rigid V cannot keep, and do so where a fold brings their
//! touch past the exclusion already overlapping; a spinning piece landing flat slips at
//! its face, not at its midline; a piece folded back across the pin meets the laid tape's
//! last node.

use super::*;

/// Half the tape's thickness (m).
const R: f64 = 0.005;

fn rod(m: f64, l: f64, at: [f64; 2], velocity_m_s: [f64; 2], spin_rad_s: f64) -> Body {
    Body {
        mass_kg: m,
        inertia_kg_m2: m * l * l / 12.0,
        position_m: at,
        angle_rad: 0.0,
        velocity_m_s,
        spin_rad_s,
    }
}

/// A straight midline of length `l` about its centre, its arc starting at `arc0` (m).
fn outline(l: f64, arc0: f64) -> Outline {
    Outline {
        nodes: vec![[-0.5 * l, 0.0], [0.5 * l, 0.0]],
        arc_m: vec![arc0, arc0 + l],
    }
}

fn layers(friction: f64, outlines: Vec<Outline>, laid: Outline) -> Layers {
    Layers {
        radius_m: R,
        friction,
        exclusion_m: std::f64::consts::FRAC_PI_2 * 2.0 * R,
        outlines,
        laid,
    }
}

/// Two rods of mass `m` and length `l` hinged at the origin, along +x and open by
/// `2 theta` about it, closing at `omega` each, as the tape's layers (friction 0.5, no laid
/// tape): the first's tip is its first node (arc 0), the hinge is at arc `l` on both, the
/// second's tip at `2 l`.
fn hinged_pair(m: f64, l: f64, theta: f64, omega: f64) -> ExactChain {
    let (c, s) = (theta.cos(), theta.sin());
    let upper = Body {
        angle_rad: theta + std::f64::consts::PI,
        ..rod(
            m,
            l,
            [0.5 * l * c, 0.5 * l * s],
            [0.5 * l * omega * s, -0.5 * l * omega * c],
            -omega,
        )
    };
    let lower = Body {
        angle_rad: -theta,
        ..rod(
            m,
            l,
            [0.5 * l * c, -0.5 * l * s],
            [0.5 * l * omega * s, 0.5 * l * omega * c],
            omega,
        )
    };
    let hinge = Joint {
        prev: [0.5 * l, 0.0],
        next: [-0.5 * l, 0.0],
    };
    let mut chain = ExactChain::new(vec![upper, lower], vec![hinge], None, TOLERANCE);
    chain.set_layers(layers(
        0.5,
        vec![outline(l, 0.0), outline(l, l)],
        Outline::default(),
    ));
    chain
}

/// The kinetic energy of `chain`'s bodies (J).
fn kinetic(chain: &ExactChain) -> f64 {
    chain
        .bodies()
        .iter()
        .map(|b| {
            let [u, w] = b.velocity_m_s;
            0.5 * b.mass_kg * (u * u + w * w) + 0.5 * b.inertia_kg_m2 * b.spin_rad_s * b.spin_rad_s
        })
        .sum()
}

/// The work the contacts of the last step did (J, negative: taken).
fn contacts_work(chain: &ExactChain) -> f64 {
    chain
        .contacts()
        .iter()
        .map(|c| c.work_j[0] + c.work_j[1])
        .sum()
}

#[test]
fn a_rod_landing_on_one_end_on_the_laid_tape_leaves_the_other_at_three_halves_its_speed() {
    // Routh's plastic impact at the face: a thin rod falling flat at V lands on one end on
    // the laid tape, bent to a ridge that meets it only there, its midline one thickness
    // (2 R) and 1 nm above the ridge's node. The contact is at the rod's face, R below its
    // midline, and sticks: the angular momentum about it, m V l / 2, is kept, with the
    // inertia m (l^2 / 3 + R^2) about it. So omega = V (l / 2) / (l^2 / 3 + R^2), the far
    // end (at sqrt(l^2 + R^2) from the contact) leaves at omega sqrt(l^2 + R^2), and the
    // impact takes m V^2 / 2 (1 - (l / 2)^2 / (l^2 / 3 + R^2)): 3 V / 2 and m V^2 / 8, the
    // floor's thin-rod answer, as R goes to 0 (here 0.6 % and 2.2 % from them). Bounds: the
    // speed within 1e-3, as on the floor (measured within 4e-5: the speed is read at the
    // step's end, the rod turned by up to 1.5 mrad over the ridge), the loss within 1e-6
    // (measured within 1e-8).
    let (l, m) = (0.1, 0.05);
    for (v, h) in [(1.0, 1e-4), (2.0, 1e-5), (0.3, 1e-3)] {
        let body = rod(m, l, [0.5 * l, 2.0 * R + 1e-9], [0.0, -v], 0.0);
        let mut chain = ExactChain::new(vec![body], Vec::new(), None, TOLERANCE);
        let laid = Outline {
            nodes: vec![[-0.1, -0.1], [0.0, 0.0], [0.1, -0.1]],
            arc_m: vec![0.0, 0.1, 0.2],
        };
        chain.set_layers(layers(1.0, vec![outline(l, 1.0)], laid));
        let report = chain.step(h, [0.0, 0.0]).expect("solves");
        assert!(report.converged, "{report:?}");
        let b = chain.bodies()[0];
        let far = b.velocity_at(b.arm([0.5 * l, 0.0]));
        let speed = far[0].hypot(far[1]);
        let about = l * l / 3.0 + R * R;
        let omega = v * 0.5 * l / about;
        let far_want = omega * l.hypot(R);
        let want = 0.5 * m * v * v * (1.0 - 0.25 * l * l / about);
        let lost = -contacts_work(&chain);
        println!(
            "V = {v} m/s, h = {h} s: the far end at {:.9} of Routh's, the laid tape took \
             {:.9} of his loss",
            speed / far_want,
            lost / want
        );
        assert!(
            (speed / far_want - 1.0).abs() < 1e-3,
            "the far end at {speed} m/s, expected {far_want} m/s"
        );
        assert!(
            (lost / want - 1.0).abs() < 1e-6,
            "the laid tape took {lost:e} J, expected {want:e} J"
        );
        assert!(
            chain.contacts().iter().all(|c| c.on == Surface::Laid),
            "{:?}",
            chain.contacts()
        );
    }
}

#[test]
fn two_pieces_closing_like_scissors_meet_at_their_tips_and_stop_as_one_rigid_v() {
    // Two rods hinged at the origin, open by 2 theta and closing, their tips a thickness
    // (2 R) and 1 nm apart: the tips meet plastically, and with the hinge the two are one
    // rigid V. Its momentum P and its angular momentum are kept (no gravity; the spins'
    // and the orbits' parts of the angular momentum about the centre of mass cancel by
    // symmetry), so it moves on at P / 2m without turning: the impact takes all but
    // P^2 / 4m. Momenta to 1e-12 of their scale, the energy within 1e-3 of the kinetic
    // energy before.
    let (l, m) = (0.1, 0.05);
    let theta = ((R + 5e-10) / l).asin();
    for omega in [10.0, 100.0] {
        let h = 1e-3 / omega;
        let mut chain = hinged_pair(m, l, theta, omega);
        let before = momentum(&chain);
        let k0 = kinetic(&chain);
        let report = chain.step(h, [0.0, 0.0]).expect("solves");
        assert!(report.converged, "{report:?}");
        let after = momentum(&chain);
        let scale = m * omega * l * l;
        for k in 0..3 {
            assert!(
                (after[k] - before[k]).abs() < 1e-12 * scale.max(m * omega * l),
                "momentum {k}: {} before, {} after",
                before[k],
                after[k]
            );
        }
        let want = (before[0] * before[0] + before[1] * before[1]) / (4.0 * m);
        let k1 = kinetic(&chain);
        println!("omega = {omega}: {k1:.6e} J left of {k0:.6e}, P^2 / 4m = {want:.6e} J");
        assert!(
            (k1 - want).abs() < 1e-3 * k0,
            "{k1:e} J left, expected {want:e} J"
        );
        let spins: Vec<f64> = chain.bodies().iter().map(|b| b.spin_rad_s).collect();
        assert!(spins.iter().all(|w| w.abs() < 1e-3 * omega), "{spins:?}");
        assert!(!chain.contacts().is_empty(), "the tips never met");
        assert!(
            chain
                .contacts()
                .iter()
                .all(|c| matches!(c.on, Surface::Body(_))),
            "{:?}",
            chain.contacts()
        );
    }
}

#[test]
fn a_fold_that_brings_a_touch_past_the_exclusion_already_overlapping_stops_as_a_rigid_v() {
    // Two hinged rods shorter than the thickness (l = 1.8 R): each tip always lies within
    // 2 R of the other rod, and the touch counts only where the tip's closest point on the
    // other rod is the exclusion (pi R) or more from it along the tape, l (1 + cos phi) >=
    // pi R with phi the opening: from phi* = 41.8 degrees down, where the faces already
    // overlap by 2 R - l sin phi* = 0.8 R. Closing through phi* within one step, the touch
    // starts to count at that depth; it is a contact from then on, not a depth to move out
    // of (the move, which cannot open a fold of rods this short to a gap of zero, took the
    // fold's energy with it: the bang's tolerance refused such steps at every length). The
    // tips then meet as the scissors above do: a rigid V that keeps P and takes all but
    // P^2 / 4m, within 1e-3 of the energy before, with nothing moved by position.
    let (l, m, omega) = (1.8 * R, 0.05, 10.0);
    let opening = (std::f64::consts::PI * R / l - 1.0).acos();
    let theta = 0.5 * opening + 0.002;
    let h = 0.004 / omega;
    let mut chain = hinged_pair(m, l, theta, omega);
    let k0 = kinetic(&chain);
    let before = momentum(&chain);
    let want = (before[0] * before[0] + before[1] * before[1]) / (4.0 * m);
    // Bounded, so that a move's realignment is taken out and reported; the bound itself
    // refuses nothing.
    let bound = ErrorBound {
        least_j: -k0,
        most_j: k0,
        tolerance: 1.0,
    };
    let mut moved = 0.0;
    for _ in 0..3 {
        let report = chain.step_bounded(h, [0.0, 0.0], bound).expect("solves");
        assert!(report.converged, "{report:?}");
        moved += report.projection_j;
    }
    let k1 = kinetic(&chain);
    let opening_now = chain.bodies()[1].angle_rad.abs() * 2.0;
    println!(
        "closed to {:.3} degrees (from {:.3}, the touch counts below {:.3}); {k1:.6e} J left \
         of {k0:.6e}, P^2 / 4m = {want:.6e} J; the moves took {moved:.3e} J",
        opening_now.to_degrees(),
        (2.0 * theta).to_degrees(),
        opening.to_degrees()
    );
    assert!(opening_now < opening, "the fold never passed phi*");
    assert!(moved == 0.0, "moves by position took {moved:e} J");
    assert!(
        (k1 - want).abs() < 1e-3 * k0,
        "{k1:e} J left, expected {want:e} J"
    );
}

#[test]
fn a_spinning_piece_landing_flat_slips_at_its_face_not_its_midline() {
    // A rod landing flat at V on its middle (the floor's one contact point, under its
    // centre) while it spins at omega and its centre moves at u = -omega R: its face, R
    // below the midline, moves at u + omega R = 0 along the floor, so sticking friction has
    // nothing to stop and takes nothing, and the rod keeps u and omega. Were friction
    // applied at the midline, the contact would slip at u and friction would take energy
    // and spin. The impact takes m V^2 / 2 and no more (1e-3).
    let (l, m, v) = (0.05, 0.02, 1.0);
    for omega in [40.0, 400.0] {
        let u = -omega * R;
        let body = rod(m, l, [0.0, R + 1e-9], [u, -v], omega);
        let mut chain = ExactChain::new(vec![body], Vec::new(), None, TOLERANCE);
        chain.set_floor(level_floor(1.0), &[vec![[0.0, 0.0]]]);
        chain.set_layers(layers(1.0, vec![outline(l, 0.0)], Outline::default()));
        // Short enough that the rod turns by 1e-4 rad in it.
        let h = 1e-4 / omega;
        let report = chain.step(h, [0.0, 0.0]).expect("solves");
        assert!(report.converged, "{report:?}");
        let b = chain.bodies()[0];
        let friction: f64 = chain.contacts().iter().map(|c| c.work_j[1]).sum();
        let (normal, want) = (-contacts_work(&chain), 0.5 * m * v * v);
        println!(
            "omega = {omega} rad/s: u {:.6e} m/s, omega {:.6} rad/s after; friction's work \
             {friction:.3e} J, the impact took {:.9} of m V^2 / 2",
            b.velocity_m_s[0],
            b.spin_rad_s,
            normal / want
        );
        assert!(
            friction.abs() < 1e-6 * want,
            "friction did {friction:e} J at a face that does not slip"
        );
        assert!((b.spin_rad_s / omega - 1.0).abs() < 1e-3, "{b:?}");
        assert!((b.velocity_m_s[0] / u - 1.0).abs() < 1e-3, "{b:?}");
        assert!(b.velocity_m_s[1].abs() < 1e-3 * v, "{b:?}");
        assert!((normal / want - 1.0).abs() < 1e-3, "took {normal:e} J");
    }
}

#[test]
fn a_pinned_piece_resting_on_the_laid_tape_near_its_pin_takes_the_least_impulse_that_holds_it() {
    // A rod pinned at its end rests on a ridge of the laid tape, the ridge's node at d from
    // the pin, under gravity. Its point of contact (at the face, R below the midline, at arm
    // (d, -R) from the pin) can move one way only, across its arm: the pin leaves it one
    // direction, tilted by atan(R / d) from the normal, and friction 1 holds it there. Any
    // impulse across that direction is the pin's, so the contact's own is the least that
    // holds the rod: each step, gravity's moment about the pin, m g (l / 2) h, over |arm|,
    // along the direction. Asked to hold the point's normal and tangential velocity both,
    // with one direction to move, the step answered with an impulse across it that the pin
    // cancelled and the regularisation alone bounded, its normal and friction work large and
    // opposite (at the thin tape's anchor, 121 N s on a 0.2 g piece; docs/bang-map.md).
    // Bounds: the last step's impulse within 1e-6 of the least (measured within 1e-7), the
    // rod's spin below 1e-6 rad/s, and each part of a contact's work in a step below what
    // gravity's kick gives the rod in one, m (g h)^2 (measured at a fifth of it).
    let (l, m, d, g, h) = (0.1, 0.05, 0.03, 9.81, 1e-4);
    let body = rod(m, l, [0.5 * l, 2.0 * R], [0.0, 0.0], 0.0);
    let pin = Pin {
        anchor: [-0.5 * l, 0.0],
        at_m: [0.0, 2.0 * R],
    };
    let mut chain = ExactChain::new(vec![body], Vec::new(), Some(pin), TOLERANCE);
    let laid = Outline {
        nodes: vec![[d - 0.1, -0.1], [d, 0.0], [d + 0.1, -0.1]],
        arc_m: vec![0.0, 0.1, 0.2],
    };
    chain.set_layers(layers(1.0, vec![outline(l, 1.0)], laid));
    let least = m * g * 0.5 * l * h / d.hypot(R);
    let (mut largest, mut work) = (0.0_f64, 0.0_f64);
    for _ in 0..20 {
        let report = chain.step(h, [0.0, -g]).expect("solves");
        assert!(report.converged, "{report:?}");
        let (mut p, mut w) = ([0.0; 2], 0.0_f64);
        for c in chain.contacts() {
            for (k, pk) in p.iter_mut().enumerate() {
                *pk += c.normal_n_s[k] + c.friction_n_s[k];
            }
            w = w.max(c.work_j[0].abs()).max(c.work_j[1].abs());
        }
        largest = largest.max(p[0].hypot(p[1]) / least);
        work = work.max(w);
    }
    let p: f64 = chain
        .contacts()
        .iter()
        .map(|c| {
            let p = [
                c.normal_n_s[0] + c.friction_n_s[0],
                c.normal_n_s[1] + c.friction_n_s[1],
            ];
            p[0].hypot(p[1])
        })
        .sum();
    let spin = chain.bodies()[0].spin_rad_s;
    println!(
        "the last step's impulse {:.12} of the least, the largest {largest:.3e} of it; the \
         largest work of a contact in a step {work:.3e} J; spin {spin:.3e} rad/s",
        p / least
    );
    assert!(
        (p / least - 1.0).abs() < 1e-6,
        "the impulse {p:e} N s, the least that holds the rod {least:e} N s"
    );
    assert!(spin.abs() < 1e-6, "spin {spin:e} rad/s");
    let kick = m * (g * h) * (g * h);
    assert!(
        work < kick,
        "a contact's work {work:e} J in a step, above {kick:e} J"
    );
}

#[test]
fn a_piece_folded_back_across_the_pin_meets_the_laid_tape_s_last_node() {
    // The laid tape ends where the first piece is pinned, P. That point is no laid link's
    // first node, and the pinned piece's first node is the pin's: neither side held it as a
    // node, so a piece folded back across the pin passed through it. Here the first piece
    // stands on P; the second, hinged at its top, swings down past P, its line 2R + 2 mm
    // from it, at 1 rad/s (no gravity). Nothing else is within reach of it. Unmet, it would
    // swing to 6 mm of P (0.8 R deep) within the 600 steps; met, it stops at the touch.
    let (m, l0, h) = (0.05, 0.1, 1e-4);
    let phi = ((2.0 * R + 0.002) / l0).asin();
    let l1 = 2.0 * l0 * phi.cos();
    let dir = [phi.sin(), -phi.cos()];
    let top = [0.0, l0];
    let omega = -1.0;
    let arm = [0.5 * l1 * dir[0], 0.5 * l1 * dir[1]];
    let first = Body {
        angle_rad: std::f64::consts::FRAC_PI_2,
        ..rod(m, l0, [0.0, 0.5 * l0], [0.0, 0.0], 0.0)
    };
    let second = Body {
        angle_rad: dir[1].atan2(dir[0]),
        ..rod(
            m,
            l1,
            [top[0] + arm[0], top[1] + arm[1]],
            [-omega * arm[1], omega * arm[0]],
            omega,
        )
    };
    let hinge = Joint {
        prev: [0.5 * l0, 0.0],
        next: [-0.5 * l1, 0.0],
    };
    let pin = Pin {
        anchor: [-0.5 * l0, 0.0],
        at_m: [0.0, 0.0],
    };
    let mut chain = ExactChain::new(vec![first, second], vec![hinge], Some(pin), TOLERANCE);
    let laid = Outline {
        nodes: vec![[-0.2, 0.0], [-0.1, 0.0], [0.0, 0.0]],
        arc_m: vec![0.0, 0.1, 0.2],
    };
    chain.set_layers(layers(
        0.5,
        vec![outline(l0, 0.2), outline(l1, 0.2 + l0)],
        laid,
    ));
    // How far P lies from the second piece's midline (m).
    let distance = |chain: &ExactChain| {
        let b = &chain.bodies()[1];
        let (a, c) = (b.point([-0.5 * l1, 0.0]), b.point([0.5 * l1, 0.0]));
        let e = [c[0] - a[0], c[1] - a[1]];
        let t = (-(a[0] * e[0] + a[1] * e[1]) / (e[0] * e[0] + e[1] * e[1])).clamp(0.0, 1.0);
        (a[0] + t * e[0]).hypot(a[1] + t * e[1])
    };
    let mut closest = f64::INFINITY;
    for _ in 0..600 {
        chain.step(h, [0.0, 0.0]).expect("solves");
        closest = closest.min(distance(&chain));
    }
    println!("closest approach {closest:.6e} m, 2R = {:.1e} m", 2.0 * R);
    assert!(
        closest > 2.0 * R - 1e-6,
        "the second piece came {closest:e} m from the pin, 2R = {:e} m",
        2.0 * R
    );
}
