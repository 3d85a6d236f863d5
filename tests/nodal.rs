//! Property tests of the nodal chain's step (`model::nodal`): random chains of 1 to 200
//! pieces in random poses, spinning up to 1e7 rad/s, pinned or free, on level and sloped
//! floors, stepped at 0.02-0.6 rad a step. A step never panics; it ends with every value
//! finite and every piece's length within the tolerance, or it fails cleanly (the chain
//! left as it was); the chain's energy never rises above its start but for what the
//! projection out of the floor adds, which the step reports. Case count: `PROPTEST_CASES`
//! (default 64; each case steps its chain 40 times).

use proptest::prelude::*;
use proptest::test_runner::FileFailurePersistence;
use uncoil::model::exact_chain::{Floor, Tolerance};
use uncoil::model::nodal::{NodalChain, Piece};

/// A chain as the property draws it.
#[derive(Debug, Clone)]
struct Drawn {
    pieces: usize,
    /// Each piece's direction (rad) and spin (rad/s).
    angles: Vec<f64>,
    spins: Vec<f64>,
    height_m: f64,
    fall_m_s: f64,
    pinned: bool,
    /// The floor's slope (rad) and friction.
    slope: f64,
    friction: f64,
    /// The step's turn of the fastest piece (rad).
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
                        pieces: n,
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

/// The chain of `d`: pieces of 1 mm and 1 mg (thin rods) laid from a node `height_m` above
/// the floor, every node's velocity what the pieces' spins give it, falling at `fall_m_s`.
fn chain_of(d: &Drawn) -> NodalChain {
    let l = 1e-3;
    let mut nodes = vec![[0.0, d.height_m]];
    let mut velocities = vec![[0.0, if d.pinned { 0.0 } else { d.fall_m_s }]];
    for k in 0..d.pieces {
        let (s, c) = d.angles[k].sin_cos();
        let (x, v) = (nodes[k], velocities[k]);
        nodes.push([x[0] + l * c, x[1] + l * s]);
        let w = d.spins[k];
        velocities.push([v[0] - w * l * s, v[1] + w * l * c]);
    }
    let rod = Piece {
        mass_kg: 1e-6,
        centre: [0.5, 0.0],
        gyration: 1.0 / 3.0,
        length_m: l,
        chord_angle_rad: 0.0,
    };
    let tolerance = Tolerance {
        position_m: 1e-9 * l,
        max_iterations: 50,
        max_turn_rad: 2.0 * d.turn,
    };
    let mut chain = NodalChain::new(nodes, velocities, vec![rod; d.pieces], d.pinned, tolerance);
    let floor = Floor {
        point_m: [0.0, 0.0],
        normal: [-d.slope.sin(), d.slope.cos()],
        friction: d.friction,
    };
    let points: Vec<Vec<[f64; 2]>> = (0..d.pieces)
        .map(|i| {
            if i == 0 && !d.pinned {
                vec![[0.0, 0.0], [1.0, 0.0]]
            } else {
                vec![[1.0, 0.0]]
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

proptest! {
    // Failing cases are kept in proptest-regressions/nodal.txt (commit it) and rerun first.
    #![proptest_config(ProptestConfig {
        failure_persistence: Some(Box::new(FileFailurePersistence::Direct(
            "proptest-regressions/nodal.txt",
        ))),
        ..ProptestConfig::with_cases(cases())
    })]

    #[test]
    fn a_step_stays_finite_closed_and_never_gives_energy(d in drawn()) {
        let mut chain = chain_of(&d);
        let g = [0.0, -9.81];
        let energy = |c: &NodalChain| c.kinetic_j() + c.potential_j(g);
        let e0 = energy(&chain);
        let scale = chain.kinetic_j() + 1e-6 * 9.81 * 0.01 * d.pieces as f64;
        let mut lifted = 0.0;
        for _ in 0..40 {
            let fastest = (0..d.pieces)
                .map(|i| chain.body(i).spin_rad_s.abs())
                .fold(1.0, f64::max);
            let before: Vec<[f64; 2]> = chain.nodes().to_vec();
            match chain.step((d.turn / fastest).min(1e-3), g) {
                Ok(report) => {
                    lifted += report.projection_j.max(0.0);
                    let finite = chain.nodes().iter().chain(chain.velocities()).flatten();
                    prop_assert!(finite.into_iter().all(|x| x.is_finite()));
                    let open = chain.length_error_m();
                    prop_assert!(open <= chain.position_tolerance_m(), "a piece open by {open:e} m");
                    let rise = energy(&chain) - e0 - lifted;
                    prop_assert!(rise <= 1e-9 * scale, "the energy rose by {rise:e} J of {scale:e}");
                }
                Err(_) => {
                    // Failed cleanly: the chain as it was.
                    prop_assert_eq!(chain.nodes(), &before[..]);
                    break;
                }
            }
        }
    }
}
