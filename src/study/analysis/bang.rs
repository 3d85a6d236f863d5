//! The final bang's studies: per varied key and setting of the others, each setting an
//! ensemble of repetitions, each observable its mean, the standard error of that mean and
//! the fitted order of its change from the finest setting. Numbers only: their Markdown
//! table is in [`report`](super::report).

use std::collections::BTreeMap;

use super::{PowerFit, fit_power, fitting_rows, is_resolution, pareto_front, step_size, tied_keys};
use crate::study::sweep::{Col, SweepTable};

/// How a bang study reads an observable from a sweep row.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Reading {
    /// A column as it is.
    Column(Col),
    /// What the bang dissipated over what it received.
    DissipatedOfKineticIn,
    /// How far the free end stopped short of the tape lying flat (m).
    ShortOfFlat,
    /// The bang's engine time over the unroll's.
    CostOfUnroll,
}

/// The final bang's observables a bang study follows: a label and how to read it from a
/// sweep row (`NaN` where the run has no bang).
pub const BANG_OBSERVABLES: [(&str, Reading); 15] = [
    ("dissipated / kinetic in", Reading::DissipatedOfKineticIn),
    (
        "floor impacts share",
        Reading::Column(Col::BangFloorNormalOf),
    ),
    (
        "floor friction share",
        Reading::Column(Col::BangFloorFrictionOf),
    ),
    (
        "layers' impacts share",
        Reading::Column(Col::BangLayersNormalOf),
    ),
    (
        "layers' friction share",
        Reading::Column(Col::BangLayersFrictionOf),
    ),
    ("freezing share", Reading::Column(Col::BangFreezeOf)),
    ("numerical share", NUMERICAL),
    ("top speed (m/s)", Reading::Column(Col::BangTopSpeed)),
    ("duration (s)", Reading::Column(Col::BangDuration)),
    (
        "peak floor force (N)",
        Reading::Column(Col::BangPeakFloorForce),
    ),
    (
        "floor impulse (N s)",
        Reading::Column(Col::BangFloorImpulse),
    ),
    ("end short of flat (m)", Reading::ShortOfFlat),
    ("bang wall / unroll wall", Reading::CostOfUnroll),
    (
        "still moving / kinetic in",
        Reading::Column(Col::BangStillMovingOf),
    ),
    ("bang wall (s)", Reading::Column(Col::BangWall)),
];

/// The bang's cost in a bang study's front: its engine time, s.
pub const BANG_COST: Reading = Reading::Column(Col::BangWall);

/// A setting whose numerical share (joints and residual, of what the bang dissipated)
/// exceeds this in size is marked in the tables and the pictures: its split is not the
/// physics' alone.
pub const NUMERICAL_MARK: f64 = 0.01;

/// The numerical share, whose limit is zero: its order is fitted to the mean itself.
pub const NUMERICAL: Reading = Reading::Column(Col::BangNumericalOf);

/// The final bang in one varied key, the others held: a chaotic process, so each
/// setting is an ensemble (the repetitions, e.g. pushes differing in the fourth digit) and
/// each observable its mean with the standard error of that mean.
#[derive(Debug, Clone, PartialEq)]
pub struct BangStudy {
    /// The varied key.
    pub key: String,
    /// Keys varied together with it ([`tied_keys`]), each a function of it.
    pub tied: Vec<String>,
    /// The other keys' settings, `k=v k=v`.
    pub group: String,
    /// Whether the key is physical ([`is_resolution`]): its settings then run from the
    /// smallest value up, `h` holds the values themselves and nothing is fitted.
    pub physical: bool,
    /// The key's settings, coarsest first (a physical key's, smallest first).
    pub values: Vec<f64>,
    /// Step sizes ([`step_size`]) of the settings; a physical key's values.
    pub h: Vec<f64>,
    /// Runs (with a bang) per setting.
    pub n: Vec<usize>,
    /// Per observable of [`BANG_OBSERVABLES`]: mean per setting.
    pub mean: Vec<Vec<f64>>,
    /// Per observable: standard error of the mean per setting (`NaN` with one run).
    pub se: Vec<Vec<f64>>,
    /// Per observable: fit of |mean - the finest setting's mean| against h (the finest
    /// setting excluded); for the numerical share, whose limit is zero, of the mean itself.
    pub fit: Vec<Option<PowerFit>>,
    /// Whether this is the sweep's one ensemble: no key takes two settings but the
    /// repetitions (`key` names them), every run pooled as one setting.
    pub pooled: bool,
}

/// The bang studies of a sweep with bang columns: one per numeric varied key and setting
/// of the other keys, the `repeats` pooled as the ensemble, over the runs whose bang took
/// time. Where no key but the repetitions takes two settings, one study of every run
/// pooled ([`BangStudy::pooled`]). Empty if the sweep has no bang columns, or no key takes
/// two settings and none is a repetition.
pub fn bang_studies(table: &SweepTable, repeats: &[String]) -> Vec<BangStudy> {
    let Some((values, landed)) = observed(table) else {
        return Vec::new();
    };
    let rows = table.rows.len();
    let landed = |r: usize| landed[r];
    let tied = tied_keys(table);
    // A key varied with another (a function of it) is studied as that key's companion.
    let keys: Vec<String> = table
        .varied_keys()
        .into_iter()
        .filter(|k| !repeats.contains(k) && !tied.contains_key(k))
        .collect();
    let cell = |r: usize, k: &str| table.rows[r][table.column(k).expect("a varied key")].clone();
    let mut studies = Vec::new();
    for key in &keys {
        let Some(vals) = table
            .numbers(key)
            .filter(|v| v.iter().all(|x| x.is_finite()))
        else {
            continue;
        };
        // Group the runs with a bang by the other (non-repeat) keys, then by this key.
        let mut groups: BTreeMap<String, BTreeMap<u64, Vec<usize>>> = BTreeMap::new();
        for r in (0..rows).filter(|&r| landed(r)) {
            let g = keys
                .iter()
                .filter(|k| *k != key)
                .map(|k| format!("{k}={}", cell(r, k)))
                .collect::<Vec<_>>()
                .join(" ");
            groups
                .entry(g)
                .or_default()
                .entry(vals[r].to_bits())
                .or_default()
                .push(r);
        }
        for (group, by_value) in groups {
            if by_value.len() < 2 {
                continue;
            }
            let mut study = ensemble_study(key, group, by_value, &values);
            study.tied = tied
                .iter()
                .filter(|(_, lead)| *lead == key)
                .map(|(k, _)| k.clone())
                .collect();
            studies.push(study);
        }
    }
    let all: Vec<usize> = (0..rows).filter(|&r| landed(r)).collect();
    if studies.is_empty() && !repeats.is_empty() && all.len() >= 2 {
        let mut pooled = ensemble_study(
            &repeats.join(", "),
            String::new(),
            BTreeMap::from([(0.0_f64.to_bits(), all)]),
            &values,
        );
        pooled.pooled = true;
        studies.push(pooled);
    }
    studies
}

/// Each of [`BANG_OBSERVABLES`] read from every row of `table` (`NaN` where a row lacks
/// it), and whether each row's bang counts: a run that [fits](super::RowStatus::fits) and
/// whose bang took time (`stop.bang_cap_s = 0` gives it none, and nothing to say). `None`
/// if the table has no bang columns.
pub(super) fn observed(table: &SweepTable) -> Option<(Vec<Vec<f64>>, Vec<bool>)> {
    let col = |c: Col| table.col(c);
    let (Some(kin), Some(diss), Some(laid), Some(end), Some(bw), Some(rw), Some(duration)) = (
        col(Col::BangKineticIn),
        col(Col::BangDissipated),
        col(Col::BangLaidLength),
        col(Col::BangEndX),
        col(Col::BangWall),
        col(Col::WallRolling),
        col(Col::BangDuration),
    ) else {
        return None;
    };
    let rows = table.rows.len();
    let fits = fitting_rows(table).unwrap_or_else(|| vec![true; rows]);
    let values: Vec<Vec<f64>> = BANG_OBSERVABLES
        .iter()
        .map(|(_, reading)| match *reading {
            Reading::DissipatedOfKineticIn => (0..rows).map(|r| diss[r] / kin[r]).collect(),
            Reading::ShortOfFlat => (0..rows).map(|r| laid[r] - end[r]).collect(),
            Reading::CostOfUnroll => (0..rows).map(|r| bw[r] / rw[r]).collect(),
            Reading::Column(c) => col(c).unwrap_or_else(|| vec![f64::NAN; rows]),
        })
        .collect();
    let landed = (0..rows)
        .map(|r| fits[r] && kin[r].is_finite() && duration[r] > 0.0)
        .collect();
    Some((values, landed))
}

impl BangStudy {
    /// Whether setting `i`'s numerical share exceeds [`NUMERICAL_MARK`] in size.
    pub fn numerical_marked(&self, i: usize) -> bool {
        self.mean[observable(NUMERICAL)][i].abs() > NUMERICAL_MARK
    }

    /// The bang's speed against its error: per setting, its mean engine time (s,
    /// [`BANG_COST`]) and the size of its mean numerical share, each with its standard
    /// error.
    pub fn speed_and_error(&self) -> Vec<[f64; 4]> {
        let (c, e) = (observable(BANG_COST), observable(NUMERICAL));
        (0..self.values.len())
            .map(|i| {
                [
                    self.mean[c][i],
                    self.se[c][i],
                    self.mean[e][i].abs(),
                    self.se[e][i],
                ]
            })
            .collect()
    }

    /// The settings on the bang's Pareto front, cheapest first: those no other setting
    /// beats both in its mean engine time and in the size of its mean numerical share. Empty
    /// for a physical key's study or the pooled ensemble: their settings are no steps to
    /// choose between.
    pub fn front(&self) -> Vec<usize> {
        if self.physical || self.pooled {
            return Vec::new();
        }
        let points = self.speed_and_error();
        let cost: Vec<f64> = points.iter().map(|p| p[0]).collect();
        let err: Vec<f64> = points.iter().map(|p| p[2]).collect();
        pareto_front(&cost, &err)
    }
}

/// The index of `reading` in [`BANG_OBSERVABLES`].
pub(crate) fn observable(reading: Reading) -> usize {
    BANG_OBSERVABLES
        .iter()
        .position(|o| o.1 == reading)
        .expect("an observed reading")
}

/// The bang study of `key` in one group: `by_value` holds the rows of each setting (by the
/// bits of its value, two settings or more), `values` each observable's value per row.
fn ensemble_study(
    key: &str,
    group: String,
    by_value: BTreeMap<u64, Vec<usize>>,
    values: &[Vec<f64>],
) -> BangStudy {
    let mut settings: Vec<(f64, Vec<usize>)> = by_value
        .into_iter()
        .map(|(bits, rs)| (f64::from_bits(bits), rs))
        .collect();
    let physical = !is_resolution(key);
    if physical {
        settings.sort_by(|a, b| a.0.total_cmp(&b.0));
    } else {
        settings.sort_by(|a, b| step_size(key, b.0).total_cmp(&step_size(key, a.0)));
    }
    let h: Vec<f64> = settings
        .iter()
        .map(|(v, _)| if physical { *v } else { step_size(key, *v) })
        .collect();
    let (mut mean, mut se, mut fit) = (Vec::new(), Vec::new(), Vec::new());
    for (v, (_, reading)) in values.iter().zip(BANG_OBSERVABLES) {
        let stats: Vec<(f64, f64)> = settings
            .iter()
            .map(|(_, rs)| mean_and_se(rs.iter().map(|&r| v[r])))
            .collect();
        let m: Vec<f64> = stats.iter().map(|s| s.0).collect();
        if physical {
            fit.push(None);
        } else if reading == NUMERICAL {
            fit.push(fit_power(&h, &m));
        } else if m.len() < 2 {
            fit.push(None);
        } else {
            let finest = *m.last().expect("two settings");
            let change: Vec<f64> = m[..m.len() - 1]
                .iter()
                .map(|x| (x - finest).abs())
                .collect();
            fit.push(fit_power(&h[..h.len() - 1], &change));
        }
        se.push(stats.iter().map(|s| s.1).collect());
        mean.push(m);
    }
    BangStudy {
        key: key.to_owned(),
        tied: Vec::new(),
        group,
        physical,
        values: settings.iter().map(|s| s.0).collect(),
        n: settings.iter().map(|s| s.1.len()).collect(),
        h,
        mean,
        se,
        fit,
        pooled: false,
    }
}

/// Mean and standard error of the mean of the finite values (`NaN`s if none; the error is
/// `NaN` with one).
pub(super) fn mean_and_se(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let v: Vec<f64> = values.filter(|x| x.is_finite()).collect();
    let n = v.len() as f64;
    if v.is_empty() {
        return (f64::NAN, f64::NAN);
    }
    let m = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0);
    (m, (var / n).sqrt())
}
