//! The report's tables: a marked setting, and the bang's speed against its error.

use super::*;
use crate::study::analysis::BANG_COST;
use crate::study::analysis::bang::observable;

/// A physical key's study of two settings whose numerical shares are `numerical`.
fn study(numerical: [f64; 2]) -> BangStudy {
    let n = BANG_OBSERVABLES.len();
    let k = observable(NUMERICAL);
    let mut mean = vec![vec![0.5, 0.5]; n];
    mean[k] = numerical.to_vec();
    BangStudy {
        key: "floor.friction".into(),
        tied: vec!["solver.bang_step_rad".into()],
        group: String::new(),
        physical: true,
        values: vec![0.3, 1.0],
        h: vec![0.3, 1.0],
        n: vec![8, 8],
        mean,
        se: vec![vec![0.01, 0.01]; n],
        fit: vec![None; n],
        pooled: false,
    }
}

#[test]
fn a_setting_whose_numerical_share_exceeds_the_mark_is_marked_not_dropped() {
    let md = study([0.004, -0.02]).markdown();
    assert!(md.contains("| 0.3 | 8 |"), "{md}");
    assert!(md.contains("| 1 (!) | 8 |"), "{md}");
    assert!(
        md.contains("(!): the numerical share exceeds 1 % in size"),
        "{md}"
    );
    assert!(
        md.contains("varied together with `solver.bang_step_rad`"),
        "{md}"
    );
    let md = study([0.004, 0.0099]).markdown();
    assert!(!md.contains("(!)"), "{md}");
}

#[test]
fn a_tolerance_s_settings_are_ranked_by_the_bang_s_engine_time_and_error() {
    // Three tolerances: the middle one is both slower and less accurate than the
    // finest, so it is off the front; a negative share counts by its size.
    let mut b = study([0.0, 0.0]);
    let n = BANG_OBSERVABLES.len();
    b.key = "solver.bang_tolerance".into();
    b.tied.clear();
    b.physical = false;
    b.values = vec![1e-2, 3e-3, 1e-3];
    b.h = b.values.clone();
    b.n = vec![8; 3];
    b.mean = vec![vec![0.5; 3]; n];
    b.se = vec![vec![0.01; 3]; n];
    b.fit = vec![None; n];
    b.mean[observable(NUMERICAL)] = vec![0.004, -0.003, 0.001];
    b.mean[observable(BANG_COST)] = vec![1.0, 5.0, 3.0];
    assert_eq!(b.front(), vec![0, 2]);
    let md = b.markdown();
    assert!(
        md.contains("`pareto-bang-solver.bang_tolerance.svg`"),
        "{md}"
    );
    assert!(
        md.contains("| 0.01 | 1.000e0 ± 1.0e-2 | 4.000e-3 ± 1.0e-2 | yes |"),
        "{md}"
    );
    assert!(
        md.contains("| 0.003 | 5.000e0 ± 1.0e-2 | 3.000e-3 ± 1.0e-2 |  |"),
        "{md}"
    );
    assert!(
        md.contains("| 0.001 | 3.000e0 ± 1.0e-2 | 1.000e-3 ± 1.0e-2 | yes |"),
        "{md}"
    );
    // A physical key's settings are no steps to choose between.
    assert!(study([0.004, 0.001]).front().is_empty());
}
