//! Property tests of the exact chain's step (`model::exact_chain`): random chains of 1 to
//! 200 links in random poses, spinning up to 1e7 rad/s, pinned or free, on level and sloped
//! floors, stepped at 0.02-0.6 rad a step. A step never panics; it ends with every value
//! finite and every joint closed within the position tolerance, or it fails cleanly (the
//! chain left as it was). Moved from the retired nodal chain's property tests
//! (docs/history.md); their last property, that the energy never rises, is not the exact
//! chain's: RATTLE's energy error is of second order in the step, not zero (of 256 cases
//! drawn as here, 99 rose by more than 1e-9 of their kinetic energy, the most by 0.38 of it
//! at 0.58 rad a step). Case count: `PROPTEST_CASES` (default 64; each case steps its chain
//! 40 times).

use proptest::prelude::*;
use proptest::test_runner::FileFailurePersistence;
use uncoil::model::exact_chain::{Body, ExactChain, Floor, Joint, Pin, Tolerance};

/// A chain as the property draws it.
#[derive(Debug, Clone)]
struct Drawn {
    links: usize,
    /// Each link's direction (rad) and spin (rad/s).
    angles: Vec<f64>,
    spins: Vec<f64>,
    height_m: f64,
    fall_m_s: f64,
    pinned: bool,
    /// The floor's slope (rad) and friction.
    slope: f64,
    friction: f64,
    /// The step's turn of the fastest link (rad).
    turn: f64,
}

fn drawn() -> impl Strategy<Value = Drawn> {
    (1usize..=200).prop_flat_map(|n| {
        (
            prop::collection::vec(-3.2f64..3.2, n),
            prop::collection::vec(prop_oneof![-1e7f64..1e7, -1e2f64..1e2], n),
            (0.0f64..0.01, -5.0f64..1.0, any::<bool>()),
            (-0.5f64..0.5, prop_oneof![Just(0.0), 0.0f64..1.5]),
            0.02f64..0.6,
        )
            .prop_map(
                move |(angles, spins, (height_m, fall_m_s, pinned), (slope, friction), turn)| {
                    Drawn {
                        links: n,
                        angles,
                        spins,
                        height_m,
                        fall_m_s,
                        pinned,
                        slope,
                        friction,
                        turn,
                    }
                },
            )
    })
}

/// The chain of `d`: links of 1 mm and 1 mg (thin rods) laid from a node `height_m` above
/// the floor (pinned there, or falling at `fall_m_s`), every link's velocity what the spins
/// of those before it and its own give it; each link touches the floor at its far end, the
/// first of a free chain at both.
fn chain_of(d: &Drawn) -> ExactChain {
    let (l, m) = (1e-3, 1e-6);
    let mut node = [0.0, d.height_m];
    let mut node_v = [0.0, if d.pinned { 0.0 } else { d.fall_m_s }];
    let mut bodies = Vec::with_capacity(d.links);
    for (&angle, &w) in d.angles.iter().zip(&d.spins) {
        let (s, c) = angle.sin_cos();
        let half = [0.5 * l * c, 0.5 * l * s];
        bodies.push(Body {
            mass_kg: m,
            inertia_kg_m2: m * l * l / 12.0,
            position_m: [node[0] + half[0], node[1] + half[1]],
            angle_rad: angle,
            velocity_m_s: [node_v[0] - w * half[1], node_v[1] + w * half[0]],
            spin_rad_s: w,
        });
        node = [node[0] + 2.0 * half[0], node[1] + 2.0 * half[1]];
        node_v = [node_v[0] - 2.0 * w * half[1], node_v[1] + 2.0 * w * half[0]];
    }
    let (near, far) = ([-0.5 * l, 0.0], [0.5 * l, 0.0]);
    let joints = vec![
        Joint {
            prev: far,
            next: near
        };
        d.links - 1
    ];
    let pin = d.pinned.then_some(Pin {
        anchor: near,
        at_m: [0.0, d.height_m],
    });
    let tolerance = Tolerance {
        position_m: 1e-9 * l,
        max_iterations: 50,
        max_turn_rad: 2.0 * d.turn,
    };
    let mut chain = ExactChain::new(bodies, joints, pin, tolerance);
    let floor = Floor {
        point_m: [0.0, 0.0],
        normal: [-d.slope.sin(), d.slope.cos()],
        friction: d.friction,
    };
    let points: Vec<Vec<[f64; 2]>> = (0..d.links)
        .map(|i| {
            if i == 0 && !d.pinned {
                vec![near, far]
            } else {
                vec![far]
            }
        })
        .collect();
    chain.set_floor(floor, &points);
    chain
}

fn cases() -> u32 {
    std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(64)
}

/// Every coordinate and velocity of the chain's bodies is finite.
fn finite(chain: &ExactChain) -> bool {
    chain.bodies().iter().all(|b| {
        let [x, y] = b.position_m;
        let [u, w] = b.velocity_m_s;
        [x, y, b.angle_rad, u, w, b.spin_rad_s]
            .iter()
            .all(|v| v.is_finite())
    })
}

proptest! {
    // Failing cases are kept in proptest-regressions/exact_chain.txt (commit it) and rerun
    // first.
    #![proptest_config(ProptestConfig {
        failure_persistence: Some(Box::new(FileFailurePersistence::Direct(
            "proptest-regressions/exact_chain.txt",
        ))),
        ..ProptestConfig::with_cases(cases())
    })]

    #[test]
    fn a_step_stays_finite_and_closed_or_fails_cleanly(d in drawn()) {
        let mut chain = chain_of(&d);
        for _ in 0..40 {
            let fastest = chain
                .bodies()
                .iter()
                .map(|b| b.spin_rad_s.abs())
                .fold(1.0, f64::max);
            let before: Vec<Body> = chain.bodies().to_vec();
            match chain.step((d.turn / fastest).min(1e-3), [0.0, -9.81]) {
                Ok(_) => {
                    prop_assert!(finite(&chain), "a value is not finite: {:?}", chain.bodies());
                    let (open, tol) = (chain.joint_gap_m(), chain.position_tolerance_m());
                    prop_assert!(open <= tol, "a joint open by {open:e} m, expected <= {tol:e} m");
                }
                Err(_) => {
                    // Failed cleanly: the chain as it was.
                    prop_assert_eq!(chain.bodies(), &before[..]);
                    break;
                }
            }
        }
    }
}
