//! Which rows of a sweep count, and how they group: the runs that enter the fits
//! ([`fitting_rows`]), each row's setting with its repetitions pooled (`Settings`), and
//! the keys varied together with an earlier one ([`tied_keys`]). Reads a table; no text.

use std::collections::BTreeMap;

use crate::study::sweep::{RowStatus, STATUS_COLUMN, SweepTable};

/// Whether each row of a sweep table enters the fits ([`RowStatus::fits`]); `None` if the
/// table has no status column. A status that does not parse is left out.
pub fn fitting_rows(table: &SweepTable) -> Option<Vec<bool>> {
    let c = table.column(STATUS_COLUMN)?;
    Some(
        table
            .rows
            .iter()
            .map(|r| r[c].parse::<RowStatus>().is_ok_and(|s| s.fits()))
            .collect(),
    )
}

/// The sweep's settings with its repetitions pooled: per row, the first row of its setting
/// and the setting's mean cost and error over its runs that fit.
pub(super) struct Settings {
    pub(super) of: Vec<usize>,
    pub(super) cost: Vec<f64>,
    pub(super) err: Vec<f64>,
    pub(super) runs: Vec<usize>,
}

impl Settings {
    pub(super) fn new(
        table: &SweepTable,
        keys: &[String],
        repeats: &[String],
        fits: &[bool],
        cost: &[f64],
        err: &[f64],
    ) -> Self {
        let rows = table.rows.len();
        let cols: Vec<usize> = keys
            .iter()
            .filter(|k| !repeats.contains(k))
            .filter_map(|k| table.column(k))
            .collect();
        let name = |r: usize| {
            cols.iter()
                .map(|&c| table.rows[r][c].as_str())
                .collect::<Vec<_>>()
        };
        let mut first: BTreeMap<Vec<&str>, usize> = BTreeMap::new();
        let of: Vec<usize> = (0..rows)
            .map(|r| *first.entry(name(r)).or_insert(r))
            .collect();
        let mean = |v: &[f64], s: usize| {
            let x: Vec<f64> = (0..rows)
                .filter(|&r| of[r] == s && fits[r] && v[r].is_finite())
                .map(|r| v[r])
                .collect();
            (x.iter().sum::<f64>() / x.len() as f64, x.len())
        };
        let (mut c, mut e, mut runs) = (vec![f64::NAN; rows], vec![f64::NAN; rows], vec![0; rows]);
        for r in 0..rows {
            if repeats.is_empty() {
                let keep = |v: f64| if fits[r] { v } else { f64::NAN };
                (c[r], e[r], runs[r]) = (keep(cost[r]), keep(err[r]), usize::from(fits[r]));
            } else if of[r] == r {
                let ((mc, n), (me, _)) = (mean(cost, r), mean(err, r));
                (c[r], e[r], runs[r]) = (mc, me, n);
            }
        }
        for r in 0..rows {
            (c[r], e[r], runs[r]) = (c[of[r]], e[of[r]], runs[of[r]]);
        }
        Self {
            of,
            cost: c,
            err: e,
            runs,
        }
    }
}

/// The varied keys that were varied together with an earlier one (`--vary A:B=...`): each
/// such key mapped to that earlier key, its lead. A key that takes two values or more is
/// tied to an earlier key whose value fixes its own in every row: a product grid never
/// gives that (each key's values meet every value of the other), keys varied together
/// always do (the later ones may repeat a value, as a step shared by two thicknesses).
pub fn tied_keys(table: &SweepTable) -> BTreeMap<String, String> {
    let keys = table.varied_keys();
    let column = |k: &str| -> Vec<&str> {
        let c = table.column(k).expect("a varied key is a column");
        table.rows.iter().map(|r| r[c].as_str()).collect()
    };
    // Whether `a`'s value fixes `b`'s in every row.
    let fixes = |a: &[&str], b: &[&str]| {
        let mut seen: BTreeMap<&str, &str> = BTreeMap::new();
        a.iter()
            .zip(b)
            .all(|(x, y)| *seen.entry(x).or_insert(y) == *y)
    };
    let distinct = |v: &[&str]| v.iter().collect::<std::collections::BTreeSet<_>>().len();
    let mut tied = BTreeMap::new();
    for (j, follower) in keys.iter().enumerate() {
        let f = column(follower);
        if distinct(&f) < 2 {
            continue;
        }
        let lead = keys[..j]
            .iter()
            .find(|lead| !tied.contains_key(*lead) && { fixes(&column(lead), &f) });
        if let Some(lead) = lead {
            tied.insert(follower.clone(), lead.clone());
        }
    }
    tied
}
