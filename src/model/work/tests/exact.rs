//! The same known answers on the exact chain ([`ExactChain`]): each world built as the
//! bang hands its pieces to it (bars about their centres, their ends the contact points, a
//! joint's node belonging to the bar before it), booked with [`step_work`] as the bang
//! books, and each part held to [`EXACT_TOLERANCE`] of its exact value.
//!
//! The exact chain's impulses act along the step's starting pose while its joints close at
//! the step's end, so an impact that sets the bars spinning books a little of its loss to
//! the joints: first order in the angle the bars turn in the impact's step (the kink's
//! pair, sliding: 0.02 % of the loss at 5 us, where it turns about 2e-3 rad a step after the
//! impact; 0.005 % at a quarter of that). The parts are checked at the two finer steps and
//! printed at all three.

use super::*;
use crate::model::exact_chain::{Body, ExactChain, Floor, Joint, Tolerance};

/// How close each part must come to its exact value on the exact chain: 0.1 %.
const EXACT_TOLERANCE: f64 = 1e-3;

/// The exact chain's solve: contact points and joints within 1e-12 m.
const SOLVE: Tolerance = Tolerance {
    position_m: 1e-12,
    max_iterations: 50,
    max_turn_rad: 0.3,
};

/// A small world of bars on the floor `y = 0`, stepped by the exact chain.
struct ExactBench {
    bodies: Vec<Body>,
    ends: Vec<[[f64; 2]; 2]>,
    joined: usize,
    g: f64,
    friction: f64,
    chain: Option<ExactChain>,
    booked: StepWork,
}

impl ExactBench {
    fn new(g: f64, friction: f64) -> Self {
        Self {
            bodies: Vec::new(),
            ends: Vec::new(),
            joined: 0,
            g,
            friction,
            chain: None,
            booked: StepWork::default(),
        }
    }

    /// A bar from `a` to `b` of `mass`, moving at `vel`; bars are joined in the order they
    /// are made, each to the next at the next one's first end ([`Self::join_all`]).
    fn bar(&mut self, a: Vector, b: Vector, mass: f64, vel: Vector) -> usize {
        let half = 0.5 * (b - a).length();
        self.bodies.push(Body {
            mass_kg: mass,
            inertia_kg_m2: mass * (2.0 * half).powi(2) / 12.0,
            position_m: [0.5 * (a.x + b.x), 0.5 * (a.y + b.y)],
            angle_rad: (b - a).to_angle(),
            velocity_m_s: [vel.x, vel.y],
            spin_rad_s: 0.0,
        });
        self.ends.push([[-half, 0.0], [half, 0.0]]);
        self.bodies.len() - 1
    }

    /// Joins every bar to the next.
    fn join_all(&mut self) {
        self.joined = self.bodies.len();
    }

    fn chain(&mut self) -> &mut ExactChain {
        if self.chain.is_none() {
            let joints = if self.joined > 1 {
                self.ends
                    .windows(2)
                    .map(|e| Joint {
                        prev: e[0][1],
                        next: e[1][0],
                    })
                    .collect()
            } else {
                Vec::new()
            };
            let points: Vec<Vec<[f64; 2]>> = self
                .ends
                .iter()
                .enumerate()
                .map(|(i, e)| {
                    if i > 0 && self.joined > 1 {
                        vec![e[1]]
                    } else {
                        e.to_vec()
                    }
                })
                .collect();
            let mut chain = ExactChain::new(self.bodies.clone(), joints, None, SOLVE);
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
        let g = self.g;
        let chain = self.chain();
        let before: Vec<Body> = chain.bodies().to_vec();
        let report = chain.step(dt, [0.0, -g]).expect("solves");
        assert!(report.converged, "{report:?}");
        let state = |b: &Body| BodyState {
            linvel: Vector::new(b.velocity_m_s[0], b.velocity_m_s[1]),
            angvel: b.spin_rad_s,
            kinetic_j: b.kinetic_j(),
        };
        let moved: Vec<Moved> = before
            .iter()
            .zip(chain.bodies())
            .map(|(a, b)| Moved {
                mass: a.mass_kg,
                before: state(a),
                after: state(b),
            })
            .collect();
        let floor: Vec<(usize, FloorImpulse)> = chain
            .contacts()
            .iter()
            .map(|c| {
                let impulse =
                    FloorImpulse::of_chain(c.normal_n_s, c.friction_n_s, c.arm_m, c.work_j);
                (c.body, impulse)
            })
            .collect();
        let w = step_work(
            &moved,
            &floor,
            Vector::new(0.0, -g),
            dt,
            (Some(report.gravity_work_j), 0.0),
        );
        self.booked.normal_j += w.normal_j;
        self.booked.friction_j += w.friction_j;
        self.booked.joints_j += w.joints_j;
        floor.iter().map(|(_, c)| c.normal.length()).sum()
    }

    fn run_to_rest(&mut self, dt: f64, max_steps: usize) {
        for _ in 0..max_steps {
            self.step(dt);
            let moving = self.chain().bodies().iter().any(|b| {
                b.velocity_m_s[0].hypot(b.velocity_m_s[1]) + b.spin_rad_s.abs() * 0.01 > 1e-6
            });
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
        let bodies = self.chain().bodies();
        bodies
            .iter()
            .map(|b| b.mass_kg * (y0 - b.position_m[1]))
            .sum()
    }
}

/// A gap below the step's reach: the bodies start just above the floor.
const GAP: f64 = 1e-7;

/// The steps each case is run at, as fractions of its own (5 us through an impact, 50 us to
/// rest); the first is printed, not checked (see the module's doc).
const SCALES: [f64; 3] = [1.0, 0.25, 0.125];

/// Each case at every step of [`SCALES`], every part within [`EXACT_TOLERANCE`] at the
/// checked ones.
fn at_both_steps(name: &str, case: impl Fn(f64) -> Vec<(String, StepWork, (f64, f64))>) {
    let mut off = Vec::new();
    for (k, scale) in SCALES.into_iter().enumerate() {
        for (label, booked, exact) in case(scale) {
            let label = format!("exact chain, {name}, {label}, step x{scale}");
            if !check_within(&label, booked, exact, EXACT_TOLERANCE) && k > 0 {
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
    let mut bench = ExactBench::new(9.81, mu);
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
fn a_bar_landing_flat_is_split_exactly_on_the_exact_chain() {
    at_both_steps("bar, flat", |scale| {
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
    let mut bench = ExactBench::new(0.0, mu);
    let (m, l) = (0.005, 0.01);
    let half = 0.5 * l * Vector::new(tilt.cos(), tilt.sin());
    let low = Vector::new(0.0, GAP);
    bench.bar(low, low + 2.0 * half, m, Vector::new(u, -w));
    bench.run_through_impact(5e-6 * scale, 20_000);
    let w_inv = body_inverse_mass(m, m * l * l / 12.0, [-half.x, -half.y]);
    (bench.booked, plastic_impact(w_inv, [u, -w], mu))
}

#[test]
fn a_tilted_bar_s_impact_is_split_as_routh_s_on_the_exact_chain() {
    at_both_steps("bar, tilted", |scale| {
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
    let mut bench = ExactBench::new(0.0, mu);
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
fn a_two_link_chain_landing_is_split_exactly_on_the_exact_chain() {
    at_both_steps("pair", |scale| {
        let mut bench = ExactBench::new(9.81, 0.5);
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
fn a_chain_sliding_to_rest_gives_its_kinetic_energy_to_friction_on_the_exact_chain() {
    at_both_steps("chain of 8, sliding", |scale| {
        let mut bench = ExactBench::new(9.81, 0.5);
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
