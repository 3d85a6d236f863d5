//! Reads a sweep table and works out what it says: the Pareto front of error against
//! wall time, convergence orders fitted by least squares in log-log, the rate at which the
//! energy lost before the bang falls, the per-step cost against the number of links, and
//! the Markdown report. Pure `f64` and text; it runs nothing and draws nothing.
//!
//! This file holds the analysis and its convergence studies; the power fits and the
//! Pareto front are in `fit`, which rows count and how they group in `rows`, the final
//! bang's ensembles in `bang`, one setting's ensemble pooled in `ensemble`, the Markdown in
//! `report`.

mod bang;
mod ensemble;
mod fit;
mod report;
mod rows;

use std::collections::BTreeMap;

pub use self::bang::{
    BANG_COST, BANG_OBSERVABLES, BangStudy, NUMERICAL, NUMERICAL_MARK, Reading, bang_studies,
};
pub use self::ensemble::{Ensemble, Pooled};
pub use self::fit::{PowerFit, fit_power, is_resolution, pareto_front, step_size};
pub use self::rows::{fitting_rows, tied_keys};

use self::rows::Settings;

use crate::study::sweep::{Col, ERR_GEO_PREFIX, STATUS_COLUMN, SweepTable};

/// Which error a report uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Reference {
    /// The exact-geometry model (`max_err_geo`): the simulation's own error.
    Exact,
    /// Eq. (7) (`max_err_eq7`).
    Eq7,
}

impl Reference {
    /// The sweep column holding this error.
    pub fn column(self) -> Col {
        match self {
            Reference::Exact => Col::MaxErrGeo,
            Reference::Eq7 => Col::MaxErrEq7,
        }
    }

    /// A label for plots and tables.
    pub fn label(self) -> &'static str {
        match self {
            Reference::Exact => "exact-geometry model",
            Reference::Eq7 => "eq. (7)",
        }
    }
}

/// Convergence in one varied key, with the other varied keys held at one setting.
#[derive(Debug, Clone, PartialEq)]
pub struct Study {
    /// The varied key.
    pub key: String,
    /// The other keys' settings, `k=v k=v` (empty if only one key varies).
    pub group: String,
    /// Row indices of the table, sorted by step size, largest first.
    pub rows: Vec<usize>,
    /// Step sizes ([`step_size`]) of the rows.
    pub h: Vec<f64>,
    /// Errors of the rows (the report's reference).
    pub err: Vec<f64>,
    /// Energy lost before the bang over E0.
    pub lost: Vec<f64>,
    /// Links of the rows.
    pub links: Vec<f64>,
    /// Wall time per step of the rows (s).
    pub wall_per_step_s: Vec<f64>,
    /// Self-convergence: the largest relative difference of the milestone times from
    /// those of the study's finest run (`NaN` for the finest run itself).
    pub self_err: Vec<f64>,
    /// Error against step size.
    pub err_fit: Option<PowerFit>,
    /// Self-convergence against step size (the finest run excluded). It measures the
    /// order of a key whose own error hides under another's (e.g. the time step under
    /// the resolution error), and is biased high near the finest run.
    pub self_fit: Option<PowerFit>,
    /// Energy lost before the bang against step size.
    pub lost_fit: Option<PowerFit>,
    /// Wall time per step against links (the per-step cost slope).
    pub cost_fit: Option<PowerFit>,
}

/// Everything a report says about a sweep table.
#[derive(Debug, Clone)]
pub struct SweepAnalysis {
    /// The table.
    pub table: SweepTable,
    /// Whether each row enters the fits, the front and the target
    /// ([`RowStatus::fits`](crate::study::sweep::RowStatus::fits)): runs that failed, were
    /// interrupted or were stopped by a guard are left out.
    pub fits: Vec<bool>,
    /// The error used.
    pub reference: Reference,
    /// Wall-time column used as the cost (`wall_rolling_s` or `wall_s`).
    pub cost_column: String,
    /// Cost of each row (s); `NaN` for a failed row.
    pub cost: Vec<f64>,
    /// Error of each row; `NaN` where a milestone was not reached.
    pub err: Vec<f64>,
    /// The series each row belongs to (the settings of `series_keys`).
    pub series: Vec<String>,
    /// Keys whose values name the series.
    pub series_keys: Vec<String>,
    /// Each row's setting: the first row with its settings of the keys that are not
    /// repetitions (itself where nothing is pooled).
    pub setting: Vec<usize>,
    /// Per row, its setting's cost and error: the means over the setting's runs that fit
    /// (the row's own where nothing is pooled).
    pub setting_cost: Vec<f64>,
    /// See [`SweepAnalysis::setting_cost`].
    pub setting_err: Vec<f64>,
    /// Per row, how many runs its setting's means are of.
    pub setting_runs: Vec<usize>,
    /// The settings on the Pareto front (each by its first row, [`SweepAnalysis::setting`]),
    /// by cost: a repetition (a push) is never a setting to choose.
    pub front: Vec<usize>,
    /// One study per numeric varied key and setting of the others.
    pub studies: Vec<Study>,
    /// A target to report against: (largest error, largest cost in s).
    pub target: Option<(f64, f64)>,
    /// The varied keys pooled as repetitions.
    pub repeats: Vec<String>,
    /// The final bang's ensembles, if the sweep has bang columns.
    pub bang: Vec<BangStudy>,
}

/// Keys that name a series in the Pareto plot when they are varied: the contact model
/// and the solver.
pub const SERIES_KEYS: [&str; 2] = ["contact.model", "solver.iterations"];

impl SweepAnalysis {
    /// Analyses `table` with errors against `reference` and cost from `cost_column`.
    /// Varied keys in `repeats` name repetitions (e.g. `name=rep1,rep2,...`): runs that
    /// differ only in them are fitted together, so a fit pools the repetitions.
    pub fn new(
        table: SweepTable,
        reference: Reference,
        cost_column: &str,
        repeats: &[String],
    ) -> anyhow::Result<Self> {
        let col = |name: &str| {
            table
                .numbers(name)
                .ok_or_else(|| anyhow::anyhow!("the sweep has no `{name}` column"))
        };
        let cost = col(cost_column)?;
        let err = col(reference.column().name())?;
        let lost = col(Col::LostBeforeBangOfE0.name())?;
        let links = col(Col::Links.name())?;
        let wall = col(Col::Wall.name())?;
        let steps = col(Col::Steps.name())?;
        let ok = fitting_rows(&table)
            .ok_or_else(|| anyhow::anyhow!("the sweep has no `{STATUS_COLUMN}` column"))?;
        let keys = table.varied_keys();
        let series_keys: Vec<String> = keys
            .iter()
            .filter(|k| SERIES_KEYS.contains(&k.as_str()))
            .cloned()
            .collect();
        let series = series_names(&table, &series_keys);
        let pooled = Settings::new(&table, &keys, repeats, &ok, &cost, &err);
        // One point per setting, at its first row; its other rows are no points.
        let first = |v: &[f64]| -> Vec<f64> {
            (0..v.len())
                .map(|r| if pooled.of[r] == r { v[r] } else { f64::NAN })
                .collect()
        };
        let front = pareto_front(&first(&pooled.cost), &first(&pooled.err));
        let columns = StudyColumns {
            err: &err,
            lost: &lost,
            links: &links,
            wall: &wall,
            steps: &steps,
            milestone_errs: milestone_errors(&table),
        };
        let studies = convergence_studies(&table, &keys, repeats, &ok, &columns);
        let bang = bang_studies(&table, repeats);
        Ok(Self {
            table,
            fits: ok,
            bang,
            reference,
            cost_column: cost_column.to_owned(),
            cost,
            err,
            series,
            series_keys,
            setting: pooled.of,
            setting_cost: pooled.cost,
            setting_err: pooled.err,
            setting_runs: pooled.runs,
            front,
            studies,
            target: None,
            repeats: repeats.to_vec(),
        })
    }

    /// Whether the sweep is one setting's ensemble: some key is a repetition, and no other
    /// key takes two values. Its runs are repetitions, none a setting to choose: the report
    /// pools them and draws no Pareto front.
    pub fn one_setting(&self) -> bool {
        !self.repeats.is_empty()
            && self
                .table
                .varied_keys()
                .iter()
                .filter(|k| !self.repeats.contains(k))
                .all(|k| {
                    let c = self.table.column(k).expect("a varied key is a column");
                    self.table
                        .rows
                        .iter()
                        .all(|r| r[c] == self.table.rows[0][c])
                })
    }

    /// The runs that meet the target (error and cost at most the target's), cheapest
    /// first; empty without a target.
    pub fn meeting_target(&self) -> Vec<usize> {
        let Some((e, c)) = self.target else {
            return Vec::new();
        };
        let mut v: Vec<usize> = (0..self.cost.len())
            .filter(|&i| self.fits[i] && self.err[i] <= e && self.cost[i] <= c)
            .collect();
        v.sort_by(|&a, &b| self.cost[a].total_cmp(&self.cost[b]));
        v
    }
}

/// The cell of varied key `k` in row `r`.
fn cell(table: &SweepTable, r: usize, k: &str) -> String {
    let c = table.column(k).expect("a varied key is a column");
    table.rows[r][c].clone()
}

/// The series of each row: the settings of `series_keys`, `k=v k=v`.
fn series_names(table: &SweepTable, series_keys: &[String]) -> Vec<String> {
    (0..table.rows.len())
        .map(|r| {
            series_keys
                .iter()
                .map(|k| format!("{k}={}", cell(table, r, k)))
                .collect::<Vec<_>>()
                .join(" ")
        })
        .collect()
}

/// The milestone errors against the exact model, one column per milestone (the
/// `err_geo_*` columns): t_sim = t_geo (1 + e).
fn milestone_errors(table: &SweepTable) -> Vec<Vec<f64>> {
    table
        .header
        .iter()
        .filter(|h| h.starts_with(ERR_GEO_PREFIX))
        .filter_map(|h| table.numbers(h))
        .collect()
}

/// The convergence studies: one per numeric varied resolution key ([`is_resolution`]) that
/// is not a repetition and per setting of the other keys, over the rows that enter the fits (`ok`), where the key
/// takes two values or more.
fn convergence_studies(
    table: &SweepTable,
    keys: &[String],
    repeats: &[String],
    ok: &[bool],
    columns: &StudyColumns<'_>,
) -> Vec<Study> {
    let mut studies = Vec::new();
    // A key varied with another is that key's companion, neither studied nor grouped by.
    let tied = tied_keys(table);
    let keys: Vec<String> = keys
        .iter()
        .filter(|k| !tied.contains_key(*k))
        .cloned()
        .collect();
    // A physical key is no resolution: nothing converges in it.
    for key in keys
        .iter()
        .filter(|k| !repeats.contains(k) && is_resolution(k))
    {
        let vals: Vec<f64> = table
            .numbers(key)
            .expect("a varied key is a column")
            .into_iter()
            .collect();
        if vals.iter().any(|v| !v.is_finite()) {
            continue; // not numeric (e.g. contact.model)
        }
        for (group, rows) in groups_of_others(table, &keys, key, repeats, ok) {
            if let Some(study) = columns.study(key, group, rows, &vals) {
                studies.push(study);
            }
        }
    }
    studies
}

/// The rows that enter the fits, grouped by the settings of the keys other than `key`
/// (`k=v k=v`), the repetitions pooled.
fn groups_of_others(
    table: &SweepTable,
    keys: &[String],
    key: &str,
    repeats: &[String],
    ok: &[bool],
) -> BTreeMap<String, Vec<usize>> {
    let mut groups: BTreeMap<String, Vec<usize>> = BTreeMap::new();
    for r in (0..table.rows.len()).filter(|&r| ok[r]) {
        let g = keys
            .iter()
            .filter(|k| *k != key && !repeats.contains(k))
            .map(|k| format!("{k}={}", cell(table, r, k)))
            .collect::<Vec<_>>()
            .join(" ");
        groups.entry(g).or_default().push(r);
    }
    groups
}

/// The columns a convergence study picks its rows from, one value per row of the table.
struct StudyColumns<'a> {
    /// The report's error.
    err: &'a [f64],
    /// Energy lost before the bang over E0.
    lost: &'a [f64],
    links: &'a [f64],
    /// Wall time of the whole run (s).
    wall: &'a [f64],
    steps: &'a [f64],
    /// [`milestone_errors`].
    milestone_errs: Vec<Vec<f64>>,
}

impl StudyColumns<'_> {
    /// The study of `key` over the `rows` of one group, whose values of the key are
    /// `vals`; `None` if the rows take fewer than two distinct values.
    fn study(&self, key: &str, group: String, mut rows: Vec<usize>, vals: &[f64]) -> Option<Study> {
        rows.sort_by(|&a, &b| step_size(key, vals[b]).total_cmp(&step_size(key, vals[a])));
        let distinct = {
            let mut v: Vec<f64> = rows.iter().map(|&r| vals[r]).collect();
            v.sort_by(f64::total_cmp);
            v.dedup_by(|a, b| (*a - *b).abs() <= 1e-12 * b.abs());
            v.len()
        };
        if distinct < 2 {
            return None;
        }
        let pick = |v: &[f64]| rows.iter().map(|&r| v[r]).collect::<Vec<f64>>();
        let h: Vec<f64> = rows.iter().map(|&r| step_size(key, vals[r])).collect();
        let e = pick(self.err);
        let l = pick(self.lost);
        let n = pick(self.links);
        let wps: Vec<f64> = rows.iter().map(|&r| self.wall[r] / self.steps[r]).collect();
        let self_err = self.self_convergence(&rows);
        Some(Study {
            key: key.to_owned(),
            group,
            err_fit: fit_power(&h, &e),
            self_fit: fit_power(&h, &self_err),
            self_err,
            lost_fit: fit_power(&h, &l),
            cost_fit: fit_power(&n, &wps),
            rows,
            h,
            err: e,
            lost: l,
            links: n,
            wall_per_step_s: wps,
        })
    }

    /// The largest relative change of a milestone time of each of `rows` from that of the
    /// last (finest) row; `NaN` for the finest itself.
    fn self_convergence(&self, rows: &[usize]) -> Vec<f64> {
        let finest = *rows.last().expect("at least two rows");
        rows.iter()
            .map(|&r| {
                if r == finest {
                    return f64::NAN;
                }
                self.milestone_errs
                    .iter()
                    .map(|m| ((1.0 + m[r]) / (1.0 + m[finest]) - 1.0).abs())
                    .fold(0.0_f64, |a, d| if d.is_nan() { f64::NAN } else { a.max(d) })
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn table(rows: &[(&str, f64, f64, f64)]) -> SweepTable {
        let header: Vec<String> = [
            "index",
            "discretisation.links_per_turn",
            "links",
            "steps",
            "wall_s",
            "wall_rolling_s",
            "max_err_geo",
            "max_err_eq7",
            "lost_before_bang_of_e0",
            "status",
        ]
        .iter()
        .map(|s| (*s).to_owned())
        .collect();
        let rows = rows
            .iter()
            .enumerate()
            .map(|(i, (n, links, wall, err))| {
                vec![
                    i.to_string(),
                    (*n).to_owned(),
                    links.to_string(),
                    "1000".into(),
                    wall.to_string(),
                    wall.to_string(),
                    err.to_string(),
                    (err + 0.07).to_string(),
                    (err * 5.0).to_string(),
                    "ok".into(),
                ]
            })
            .collect();
        SweepTable { header, rows }
    }

    #[test]
    fn analysis_fits_a_synthetic_sweep() {
        // err = 0.6 / n (order 1 in h = 1/n); wall per step flat in links.
        let t = table(&[
            ("8", 100.0, 0.1, 0.6 / 8.0),
            ("16", 200.0, 0.1, 0.6 / 16.0),
            ("32", 400.0, 0.1, 0.6 / 32.0),
        ]);
        let a = SweepAnalysis::new(t, Reference::Exact, "wall_rolling_s", &[]).unwrap();
        assert_eq!(a.studies.len(), 1);
        let s = &a.studies[0];
        assert_relative_eq!(s.err_fit.unwrap().order, 1.0, epsilon = 1e-9);
        assert_relative_eq!(s.lost_fit.unwrap().order, 1.0, epsilon = 1e-9);
        assert_relative_eq!(s.cost_fit.unwrap().order, 0.0, epsilon = 1e-9);
        // Equal cost: only the most accurate run is on the front.
        assert_eq!(a.front, vec![2]);
        // Self-convergence: no err_geo_* columns in this table, so nothing to fit.
        assert!(s.self_fit.is_none());
        let md = a.markdown("t");
        assert!(
            md.contains("| `discretisation.links_per_turn` | - |"),
            "{md}"
        );
        assert!(md.contains("| 1.00 ± 0.00 (1.000, 3) |"), "{md}");
        let mut a = a;
        a.target = Some((0.05, 0.2));
        assert_eq!(a.meeting_target(), vec![1, 2]);
        assert!(
            a.markdown("t").contains(
                "Target: error <= 5.000% in <= 0.2 s: met by 2 of 3 runs; the cheapest: \
                 discretisation.links_per_turn=16 (0.1000 s, 3.750%)."
            ),
            "{}",
            a.markdown("t")
        );
        a.target = Some((0.001, 0.2));
        assert!(a.meeting_target().is_empty());
    }

    #[test]
    fn self_convergence_is_measured_from_the_finest_run() {
        // Milestone times t = t_geo (1 + e): the finest run (n = 64) is off by -0.4% (say,
        // a resolution error), the others differ from it by 0.2 h^2 with h = 1/n.
        let mut t = table(&[
            ("8", 1.0, 0.1, 0.01),
            ("16", 1.0, 0.1, 0.01),
            ("32", 1.0, 0.1, 0.01),
            ("64", 1.0, 0.1, 0.01),
        ]);
        let e_fine = -0.004;
        t.header.insert(3, "err_geo_a".into());
        t.header.insert(4, "err_geo_b".into());
        for (row, n) in t.rows.iter_mut().zip([8.0_f64, 16.0, 32.0, 64.0]) {
            let d = if n > 60.0 { 0.0 } else { 0.2 / (n * n) };
            let e = (1.0 + e_fine) * (1.0 + d) - 1.0;
            // Milestone b differs by half as much: the largest difference counts.
            let eb = (1.0 + e_fine) * (1.0 + 0.5 * d) - 1.0;
            row.insert(3, e.to_string());
            row.insert(4, eb.to_string());
        }
        let a = SweepAnalysis::new(t, Reference::Exact, "wall_s", &[]).unwrap();
        let s = &a.studies[0];
        assert_eq!(s.key, "discretisation.links_per_turn");
        assert!(s.self_err[3].is_nan(), "the finest run has no self error");
        assert_relative_eq!(s.self_err[0], 0.2 / 64.0, max_relative = 1e-9);
        let f = s.self_fit.unwrap();
        assert_eq!(f.n, 3);
        assert_relative_eq!(f.order, 2.0, epsilon = 1e-6);
    }

    /// A table of the varied keys `keys` and then `links`, one row per `rows` entry.
    fn keyed(keys: &[&str], rows: &[&[&str]]) -> SweepTable {
        let header = std::iter::once("index")
            .chain(keys.iter().copied())
            .chain(["links"])
            .map(str::to_owned)
            .collect();
        let rows = rows
            .iter()
            .enumerate()
            .map(|(i, r)| {
                std::iter::once(i.to_string())
                    .chain(r.iter().map(|c| (*c).to_owned()))
                    .chain(["10".to_owned()])
                    .collect()
            })
            .collect();
        SweepTable { header, rows }
    }

    #[test]
    fn keys_varied_together_are_tied_to_their_lead_and_a_product_grid_ties_none() {
        // b and c varied with a (c repeats a value), d in a product with them.
        let t = keyed(
            &["a", "b", "c", "d"],
            &[
                &["1", "x", "0.1", "7"],
                &["1", "x", "0.1", "8"],
                &["2", "y", "0.1", "7"],
                &["2", "y", "0.1", "8"],
                &["3", "z", "0.2", "7"],
                &["3", "z", "0.2", "8"],
            ],
        );
        let tied = tied_keys(&t);
        assert_eq!(tied.get("b").map(String::as_str), Some("a"));
        assert_eq!(tied.get("c").map(String::as_str), Some("a"));
        assert!(
            !tied.contains_key("a") && !tied.contains_key("d"),
            "{tied:?}"
        );
        // A product grid of two keys: neither fixes the other.
        let t = keyed(
            &["a", "d"],
            &[&["1", "7"], &["1", "8"], &["2", "7"], &["2", "8"]],
        );
        assert!(tied_keys(&t).is_empty());
        // A key that takes one value is fixed, not tied.
        let t = keyed(&["a", "e"], &[&["1", "5"], &["2", "5"]]);
        assert!(tied_keys(&t).is_empty());
    }
}
