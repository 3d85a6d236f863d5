//! A step bounded in its joints' error ([`ExactChain::step_bounded`]): halved until the
//! error is within its budget, and failing, the chain left as it was, where it cannot be.

use super::*;

/// Steps `chain` for 0.2 s at `h` with its joints' error summed over the steps held within
/// `budget_j` (or each step within `tolerance` of what it moved), as the bang's tolerance
/// bounds it: returns the sum, the largest energy error, and the halvings.
fn bounded_run(chain: &mut ExactChain, h: f64, budget_j: f64, tolerance: f64) -> (f64, f64, u64) {
    let e0 = chain.kinetic_j();
    let (mut spent, mut worst, mut halvings) = (0.0_f64, 0.0_f64, 0);
    for _ in 0..(0.2 / h) as usize {
        let limit = budget_j.max(spent.abs());
        let bound = ErrorBound {
            least_j: (-limit - spent).min(0.0),
            most_j: (limit - spent).max(0.0),
            tolerance,
        };
        let report = chain.step_bounded(h, [0.0, 0.0], bound).expect("solves");
        assert!(
            bound.holds(&report) || report.pieces > 1,
            "an unhalved step outside its bound: {report:?}"
        );
        spent += report.joint_error_j();
        halvings += u64::from(report.pieces - 1);
        worst = worst.max((chain.kinetic_j() - e0).abs());
    }
    (spent, worst, halvings)
}

#[test]
fn a_bounded_step_halves_until_the_joints_error_is_within_its_budget() {
    // Free, the chain's energy changes only by the joints' work: RATTLE's error. Bounded as
    // the bang bounds it, a tolerance of 1e-5 of the energy for the sum and of what each
    // step moved for a step past it, the steps that would pass it are halved.
    let (h, tolerance) = (2e-4, 1e-5);
    let mut free = spinning_and_flexing();
    let e0 = free.kinetic_j();
    let mut unbounded: f64 = 0.0;
    for _ in 0..(0.2 / h) as usize {
        free.step(h, [0.0, 0.0]).expect("solves");
        unbounded = unbounded.max((free.kinetic_j() - e0).abs());
    }
    let mut chain = spinning_and_flexing();
    let budget = tolerance * e0;
    let (spent, worst, halvings) = bounded_run(&mut chain, h, budget, tolerance);
    println!(
        "unbounded {:.2e} of the energy; bounded: the sum {:.2e}, at worst {:.2e}, {halvings} \
         halvings",
        unbounded / e0,
        spent / e0,
        worst / e0
    );
    assert!(unbounded > 10.0 * budget, "unbounded {:e}", unbounded / e0);
    assert!(halvings > 0, "no step was halved");
    // Free, the sum is the energy's change: within the budget while it has room, and past
    // it only by steps each within the tolerance of what it moved.
    assert!(spent.abs() <= 2.0 * budget, "sum {:e}", spent / e0);
    assert!(worst <= 2.0 * budget, "energy wandered by {:e}", worst / e0);
}

#[test]
fn a_step_that_cannot_meet_its_bound_fails_and_leaves_the_chain_as_it_was() {
    // No room at all: neither a range nor a share of what the step moved. RATTLE's error is
    // never exactly zero, so even halved ten times the step fails, naming its bound.
    let mut chain = spinning_and_flexing();
    let before = chain.bodies().to_vec();
    let bound = ErrorBound {
        least_j: 0.0,
        most_j: 0.0,
        tolerance: 0.0,
    };
    let err = chain.step_bounded(2e-4, [0.0, 0.0], bound).unwrap_err();
    assert!(matches!(err, StepError::Inaccurate { .. }), "{err:?}");
    assert!(err.to_string().contains("a tolerance of 0"), "{err}");
    assert_eq!(chain.bodies(), &before[..]);
}
