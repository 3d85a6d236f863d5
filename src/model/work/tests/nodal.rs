//! The same known answers on the nodal chain ([`NodalChain`]): each world built as bars
//! between nodes (a joint a node two bars share, belonging as a contact point to the bar
//! before it), booked by the chain's own report (each contact's work its impulse times its
//! point's mean velocity over the step; the joints' part what the change of energy leaves),
//! and each part held to [`NODAL_TOLERANCE`] of its exact value at every step checked.

use super::*;
use crate::model::exact_chain::{Floor, Tolerance};
use crate::model::nodal::{NodalChain, Piece};

/// How close each part must come to its exact value on the nodal chain: 0.1 %.
const NODAL_TOLERANCE: f64 = 1e-3;

/// The nodal chain's solve: pieces' lengths and contact points within 1e-12 m.
const SOLVE: Tolerance = Tolerance {
    position_m: 1e-12,
    max_iterations: 50,
    max_turn_rad: 0.3,
};

/// A small world of bars on the floor `y = 0`, stepped by the nodal chain.
struct NodalBench {
    /// Each bar's ends, mass and velocity.
    bars: Vec<([Vector; 2], f64, Vector)>,
    joined: bool,
    g: f64,
    friction: f64,
    chain: Option<NodalChain>,
    booked: StepWork,
}

impl NodalBench {
    fn new(g: f64, friction: f64) -> Self {
        Self {
            bars: Vec::new(),
            joined: false,
            g,
            friction,
            chain: None,
            booked: StepWork::default(),
        }
    }

    /// A bar from `a` to `b` of `mass`, moving at `vel`; with [`Self::join_all`], each bar
    /// begins where the one before ends.
    fn bar(&mut self, a: Vector, b: Vector, mass: f64, vel: Vector) {
        self.bars.push(([a, b], mass, vel));
    }

    fn join_all(&mut self) {
        self.joined = true;
    }

    fn chain(&mut self) -> &mut NodalChain {
        if self.chain.is_none() {
            assert!(self.joined || self.bars.len() == 1, "one bar, or a chain");
            let at = |v: Vector| [v.x, v.y];
            let mut nodes = vec![at(self.bars[0].0[0])];
            let mut velocities = vec![at(self.bars[0].2)];
            let mut pieces = Vec::new();
            for &([a, b], m, v) in &self.bars {
                nodes.push(at(b));
                velocities.push(at(v));
                pieces.push(Piece {
                    mass_kg: m,
                    centre: [0.5, 0.0],
                    gyration: 1.0 / 3.0,
                    length_m: (b - a).length(),
                    chord_angle_rad: 0.0,
                });
            }
            let points: Vec<Vec<[f64; 2]>> = (0..pieces.len())
                .map(|i| {
                    if i == 0 {
                        vec![[0.0, 0.0], [1.0, 0.0]]
                    } else {
                        vec![[1.0, 0.0]]
                    }
                })
                .collect();
            let mut chain = NodalChain::new(nodes, velocities, pieces, false, SOLVE);
            let floor = Floor {
                point_m: [0.0, 0.0],
                normal: [0.0, 1.0],
                friction: self.friction,
            };
            chain.set_floor(floor, &points);
            self.chain = Some(chain);
        }
        self.chain.as_mut().expect("just built")
    }

    /// One step of `dt`, booked; returns the floor's normal impulse in it (N s).
    fn step(&mut self, dt: f64) -> f64 {
        let gravity = [0.0, -self.g];
        let chain = self.chain();
        let before = chain.kinetic_j() + chain.potential_j(gravity);
        let report = chain.step(dt, gravity).expect("solves");
        assert!(report.converged, "{report:?}");
        let after = chain.kinetic_j() + chain.potential_j(gravity);
        let [normal, friction] = report.floor_work_j;
        let impulse = chain.contacts().iter().map(|c| c.normal_n_s[1]).sum();
        self.booked.normal_j += normal;
        self.booked.friction_j += friction;
        // What the floor's work leaves of the change of energy: the joints' and the
        // residual's, numerical.
        self.booked.joints_j += after - before - normal - friction;
        impulse
    }

    fn run_to_rest(&mut self, dt: f64, max_steps: usize) {
        for _ in 0..max_steps {
            self.step(dt);
            let moving = self
                .chain()
                .velocities()
                .iter()
                .any(|v| v[0].hypot(v[1]) > 1e-6);
            if !moving {
                return;
            }
        }
        panic!("not at rest after {max_steps} steps");
    }

    fn run_through_impact(&mut self, dt: f64, max_steps: usize) {
        let mut started = false;
        for _ in 0..max_steps {
            let impulse = self.step(dt);
            if impulse > 0.0 {
                started = true;
            } else if started {
                return;
            }
        }
        panic!("the impact did not end within {max_steps} steps");
    }

    /// How far the bars' centres fell, summed over their masses (kg m).
    fn drop_moment(&mut self, y0: f64) -> f64 {
        let chain = self.chain();
        (0..chain.pieces().len())
            .map(|i| {
                let b = chain.body(i);
                b.mass_kg * (y0 - b.position_m[1])
            })
            .sum()
    }
}

/// A gap below the step's reach: the bodies start just above the floor.
const GAP: f64 = 1e-7;

/// The steps each case is run at, as fractions of its own (5 us through an impact, 50 us to
/// rest). Every one is checked: the step's impulses act over the step, and each one's work
/// is booked as the step realises it.
const SCALES: [f64; 3] = [1.0, 0.25, 0.125];

/// Each case at every step of [`SCALES`], every part within [`NODAL_TOLERANCE`].
fn at_every_step(name: &str, case: impl Fn(f64) -> Vec<(String, StepWork, (f64, f64))>) {
    let mut off = Vec::new();
    for scale in SCALES {
        for (label, booked, exact) in case(scale) {
            let label = format!("nodal chain, {name}, {label}, step x{scale}");
            if !check_within(&label, booked, exact, NODAL_TOLERANCE) {
                off.push(label);
            }
        }
    }
    assert!(
        off.is_empty(),
        "more than 0.1 % off the exact split: {off:?}"
    );
}

fn flat_bar(scale: f64, u: f64, w: f64, mu: f64) -> (StepWork, (f64, f64)) {
    let mut bench = NodalBench::new(9.81, mu);
    let m = 0.005;
    bench.bar(
        Vector::new(-0.005, GAP),
        Vector::new(0.005, GAP),
        m,
        Vector::new(u, -w),
    );
    bench.run_to_rest(5e-5 * scale, 400_000);
    let drop = bench.drop_moment(GAP);
    (
        bench.booked,
        (-(0.5 * m * w * w + 9.81 * drop), -0.5 * m * u * u),
    )
}

#[test]
fn a_bar_landing_flat_is_split_exactly_on_the_nodal_chain() {
    at_every_step("bar, flat", |scale| {
        let (slides, sticks) = (
            flat_bar(scale, 1.0, 1.0, 0.5),
            flat_bar(scale, 0.4, 1.0, 0.5),
        );
        vec![
            ("sliding".into(), slides.0, slides.1),
            ("sticking".into(), sticks.0, sticks.1),
        ]
    });
}

fn tilted_bar(scale: f64, tilt: f64, u: f64, w: f64, mu: f64) -> (StepWork, (f64, f64)) {
    let mut bench = NodalBench::new(0.0, mu);
    let (m, l) = (0.005, 0.01);
    let half = 0.5 * l * Vector::new(tilt.cos(), tilt.sin());
    let low = Vector::new(0.0, GAP);
    bench.bar(low, low + 2.0 * half, m, Vector::new(u, -w));
    bench.run_through_impact(5e-6 * scale, 20_000);
    let w_inv = body_inverse_mass(m, m * l * l / 12.0, [-half.x, -half.y]);
    (bench.booked, plastic_impact(w_inv, [u, -w], mu))
}

#[test]
fn a_tilted_bar_s_impact_is_split_as_routh_s_on_the_nodal_chain() {
    at_every_step("bar, tilted", |scale| {
        let mut cases = Vec::new();
        for tilt in [0.3, 1.0] {
            let (booked, exact) = tilted_bar(scale, tilt, 1.0, 1.0, 0.2);
            cases.push((format!("{tilt} rad, sliding"), booked, exact));
            let (booked, exact) = tilted_bar(scale, tilt, 0.0, 1.0, 1.0);
            cases.push((format!("{tilt} rad, sticking"), booked, exact));
        }
        cases
    });
}

fn kinked_pair(scale: f64, phi: [f64; 2], u: f64, w: f64, mu: f64) -> (StepWork, (f64, f64)) {
    let mut bench = NodalBench::new(0.0, mu);
    let (m, l) = (0.0025, 0.005);
    let kink = Vector::new(0.0, GAP);
    let ends = phi.map(|p| kink + l * Vector::new(p.cos(), p.sin()));
    let vel = Vector::new(u, -w);
    bench.bar(ends[0], kink, m, vel);
    bench.bar(kink, ends[1], m, vel);
    bench.join_all();
    bench.run_through_impact(5e-6 * scale, 20_000);
    (
        bench.booked,
        plastic_impact(kink_inverse_mass(m, l, phi), [u, -w], mu),
    )
}

#[test]
fn a_two_link_chain_landing_is_split_exactly_on_the_nodal_chain() {
    at_every_step("pair", |scale| {
        let mut bench = NodalBench::new(9.81, 0.5);
        let (m, vel) = (0.0025, Vector::new(1.0, -1.0));
        bench.bar(Vector::new(-0.005, GAP), Vector::new(0.0, GAP), m, vel);
        bench.bar(Vector::new(0.0, GAP), Vector::new(0.005, GAP), m, vel);
        bench.join_all();
        bench.run_to_rest(5e-5 * scale, 400_000);
        let drop = bench.drop_moment(GAP);
        let flat = (-m - 9.81 * drop, -m);
        let phi = [std::f64::consts::PI - 0.3, 0.8];
        let slides = kinked_pair(scale, phi, 1.0, 1.0, 0.2);
        let sticks = kinked_pair(scale, phi, 0.0, 1.0, 1.0);
        vec![
            ("flat".into(), bench.booked, flat),
            ("on its kink, sliding".into(), slides.0, slides.1),
            ("on its kink, sticking".into(), sticks.0, sticks.1),
        ]
    });
}

#[test]
fn a_chain_sliding_to_rest_gives_its_kinetic_energy_to_friction_on_the_nodal_chain() {
    at_every_step("chain of 8, sliding", |scale| {
        let mut bench = NodalBench::new(9.81, 0.5);
        let (m, u) = (0.0025, 0.5);
        for k in 0..8 {
            let x = 0.005 * f64::from(k);
            bench.bar(
                Vector::new(x, 0.0),
                Vector::new(x + 0.005, 0.0),
                m,
                Vector::new(u, 0.0),
            );
        }
        bench.join_all();
        bench.run_to_rest(5e-5 * scale, 400_000);
        vec![(
            "to rest".into(),
            bench.booked,
            (0.0, -0.5 * 8.0 * m * u * u),
        )]
    });
}
