//! Reads a sweep table and works out what it says: the Pareto front of error against
//! wall time, convergence orders fitted by least squares in log-log, the rate at which the
//! energy lost before the bang falls, the per-step cost against the number of links, and
//! the Markdown report. Pure `f64` and text; it runs nothing and draws nothing.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use crate::study::sweep::{RowStatus, STATUS_COLUMN, SweepTable};

/// A least-squares fit of `log10 y = order * log10 x + log10_c`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PowerFit {
    /// The exponent: the convergence order when `x` is a step size and `y` an error.
    pub order: f64,
    /// The intercept, `log10` of the constant.
    pub log10_c: f64,
    /// Standard error of `order` (`NaN` with 2 points).
    pub order_se: f64,
    /// Coefficient of determination of the log-log line (1 = a perfect power law).
    pub r2: f64,
    /// Points used.
    pub n: usize,
}

impl PowerFit {
    /// The fitted `y` at `x`.
    pub fn eval(&self, x: f64) -> f64 {
        10f64.powf(self.log10_c + self.order * x.log10())
    }
}

/// Fits `y = C x^order` by least squares on `(log10 x, log10 y)`, using the points where
/// both are finite and positive; `None` if fewer than 2 such points or all `x` are equal.
pub fn fit_power(x: &[f64], y: &[f64]) -> Option<PowerFit> {
    let pts: Vec<(f64, f64)> = x
        .iter()
        .zip(y)
        .filter(|(a, b)| a.is_finite() && b.is_finite() && **a > 0.0 && **b > 0.0)
        .map(|(a, b)| (a.log10(), b.log10()))
        .collect();
    let n = pts.len();
    if n < 2 {
        return None;
    }
    #[allow(clippy::cast_precision_loss)]
    let nf = n as f64;
    let mx = pts.iter().map(|p| p.0).sum::<f64>() / nf;
    let my = pts.iter().map(|p| p.1).sum::<f64>() / nf;
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let syy: f64 = pts.iter().map(|p| (p.1 - my).powi(2)).sum();
    // All x equal (to rounding): no slope to fit.
    if sxx <= 1e-12 * nf {
        return None;
    }
    let order = sxy / sxx;
    let log10_c = my - order * mx;
    let ss_res: f64 = pts
        .iter()
        .map(|p| (p.1 - (log10_c + order * p.0)).powi(2))
        .sum();
    let r2 = if syy > 0.0 { 1.0 - ss_res / syy } else { 1.0 };
    let order_se = if n > 2 {
        (ss_res / (nf - 2.0) / sxx).sqrt()
    } else {
        f64::NAN
    };
    Some(PowerFit {
        order,
        order_se,
        log10_c,
        r2,
        n,
    })
}

/// The step size a setting stands for, so that a convergence order is positive when the
/// error falls as the setting is refined: a key naming a size in its unit (`_s`, `_m`,
/// `_rad`, e.g. `solver.max_dt_s`, `solver.bang_step_rad`) is the step itself; any other
/// (a count or rate, e.g. `discretisation.links_per_turn`, `solver.steps_per_link`) gives
/// `1 / value`.
pub fn step_size(key: &str, value: f64) -> f64 {
    if key.ends_with("_s") || key.ends_with("_m") || key.ends_with("_rad") {
        value
    } else {
        1.0 / value
    }
}

/// The indices of the Pareto front: points no other point beats in both cost and error
/// (lower is better for both), sorted by cost. Non-finite points are ignored.
pub fn pareto_front(cost: &[f64], err: &[f64]) -> Vec<usize> {
    let mut idx: Vec<usize> = (0..cost.len())
        .filter(|&i| cost[i].is_finite() && err[i].is_finite())
        .collect();
    idx.sort_by(|&a, &b| cost[a].total_cmp(&cost[b]).then(err[a].total_cmp(&err[b])));
    let mut front = Vec::new();
    let mut best = f64::INFINITY;
    for i in idx {
        if err[i] < best {
            best = err[i];
            front.push(i);
        }
    }
    front
}

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
    pub fn column(self) -> &'static str {
        match self {
            Reference::Exact => "max_err_geo",
            Reference::Eq7 => "max_err_eq7",
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
    /// Whether each row enters the fits, the front and the target ([`RowStatus::fits`]):
    /// runs that failed, were interrupted or were stopped by a guard are left out.
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
    /// Row indices on the Pareto front, by cost.
    pub front: Vec<usize>,
    /// One study per numeric varied key and setting of the others.
    pub studies: Vec<Study>,
    /// A target to report against: (largest error, largest cost in s).
    pub target: Option<(f64, f64)>,
    /// The final bang's ensembles, if the sweep has bang columns.
    pub bang: Vec<BangStudy>,
}

/// The final bang's observables a bang study follows: a label and how to read it from a
/// sweep row (`None` where the run has no bang).
pub const BANG_OBSERVABLES: [(&str, &str); 10] = [
    ("dissipated / kinetic in", "dissipated"),
    ("floor normal share", "bang_floor_normal_of"),
    ("floor friction share", "bang_floor_friction_of"),
    ("numerical share", "bang_numerical_of"),
    ("top speed (m/s)", "bang_top_speed_m_s"),
    ("duration (s)", "bang_duration_s"),
    ("peak floor force (N)", "bang_peak_floor_force_n"),
    ("floor impulse (N s)", "bang_floor_impulse_n_s"),
    ("end short of flat (m)", "short"),
    ("bang wall / unroll wall", "cost"),
];

/// The final bang in one varied key, the others held: a chaotic process, so each
/// setting is an ensemble (the repetitions, e.g. pushes differing in the fourth digit) and
/// each observable its mean with the standard error of that mean.
#[derive(Debug, Clone, PartialEq)]
pub struct BangStudy {
    /// The varied key.
    pub key: String,
    /// The other keys' settings, `k=v k=v`.
    pub group: String,
    /// The key's settings, coarsest first.
    pub values: Vec<f64>,
    /// Step sizes ([`step_size`]) of the settings.
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
}

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

/// The bang studies of a sweep with bang columns: one per numeric varied key and setting
/// of the other keys, the `repeats` pooled as the ensemble, over the runs whose bang took
/// time. Empty if the sweep has no bang columns or no key takes two settings.
pub fn bang_studies(table: &SweepTable, repeats: &[String]) -> Vec<BangStudy> {
    let col = |name: &str| table.numbers(name);
    let (Some(kin), Some(diss), Some(laid), Some(end), Some(bw), Some(rw), Some(duration)) = (
        col("bang_kinetic_in_j"),
        col("bang_dissipated_j"),
        col("bang_laid_length_m"),
        col("bang_end_x_m"),
        col("bang_wall_s"),
        col("wall_rolling_s"),
        col("bang_duration_s"),
    ) else {
        return Vec::new();
    };
    let rows = table.rows.len();
    let fits = fitting_rows(table).unwrap_or_else(|| vec![true; rows]);
    let values: Vec<Vec<f64>> = BANG_OBSERVABLES
        .iter()
        .map(|(_, c)| match *c {
            "dissipated" => (0..rows).map(|r| diss[r] / kin[r]).collect(),
            "short" => (0..rows).map(|r| laid[r] - end[r]).collect(),
            "cost" => (0..rows).map(|r| bw[r] / rw[r]).collect(),
            c => col(c).unwrap_or_else(|| vec![f64::NAN; rows]),
        })
        .collect();
    let keys = table.varied_keys();
    let cell = |r: usize, k: &str| table.rows[r][table.column(k).expect("a varied key")].clone();
    let mut studies = Vec::new();
    for key in keys.iter().filter(|k| !repeats.contains(k)) {
        let Some(vals) = table
            .numbers(key)
            .filter(|v| v.iter().all(|x| x.is_finite()))
        else {
            continue;
        };
        // Group the runs with a bang by the other (non-repeat) keys, then by this key.
        let mut groups: BTreeMap<String, BTreeMap<u64, Vec<usize>>> = BTreeMap::new();
        // A bang given no time (stop.bang_cap_s = 0) has nothing to say.
        for r in (0..rows).filter(|&r| fits[r] && kin[r].is_finite() && duration[r] > 0.0) {
            let g = keys
                .iter()
                .filter(|k| *k != key && !repeats.contains(k))
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
            let mut settings: Vec<(f64, Vec<usize>)> = by_value
                .into_iter()
                .map(|(bits, rs)| (f64::from_bits(bits), rs))
                .collect();
            settings.sort_by(|a, b| step_size(key, b.0).total_cmp(&step_size(key, a.0)));
            let h: Vec<f64> = settings.iter().map(|(v, _)| step_size(key, *v)).collect();
            let (mut mean, mut se, mut fit) = (Vec::new(), Vec::new(), Vec::new());
            for (v, (_, column)) in values.iter().zip(BANG_OBSERVABLES) {
                let stats: Vec<(f64, f64)> = settings
                    .iter()
                    .map(|(_, rs)| mean_and_se(rs.iter().map(|&r| v[r])))
                    .collect();
                let m: Vec<f64> = stats.iter().map(|s| s.0).collect();
                if column == "bang_numerical_of" {
                    fit.push(fit_power(&h, &m));
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
            studies.push(BangStudy {
                key: key.clone(),
                group,
                values: settings.iter().map(|s| s.0).collect(),
                n: settings.iter().map(|s| s.1.len()).collect(),
                h,
                mean,
                se,
                fit,
            });
        }
    }
    studies
}

/// Mean and standard error of the mean of the finite values (`NaN`s if none; the error is
/// `NaN` with one).
fn mean_and_se(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let v: Vec<f64> = values.filter(|x| x.is_finite()).collect();
    #[allow(clippy::cast_precision_loss)]
    let n = v.len() as f64;
    if v.is_empty() {
        return (f64::NAN, f64::NAN);
    }
    let m = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0);
    (m, (var / n).sqrt())
}

impl BangStudy {
    /// The study as Markdown: one row per setting (mean ± standard error of each
    /// observable), then the fitted order of each observable's change from the finest
    /// setting, and whether that change is within two standard errors.
    pub fn markdown(&self) -> String {
        let mut o = String::new();
        let _ = writeln!(
            o,
            "### `{}`{}\n",
            self.key,
            if self.group.is_empty() {
                String::new()
            } else {
                format!(" ({})", self.group)
            }
        );
        let names: Vec<&str> = BANG_OBSERVABLES.iter().map(|o| o.0).collect();
        let _ = writeln!(o, "| {} | runs | {} |", self.key, names.join(" | "));
        let _ = writeln!(o, "|---|---|{}", "---|".repeat(names.len()));
        for i in 0..self.values.len() {
            let cells: Vec<String> = (0..names.len())
                .map(|k| show_mean(self.mean[k][i], self.se[k][i]))
                .collect();
            let _ = writeln!(
                o,
                "| {} | {} | {} |",
                self.values[i],
                self.n[i],
                cells.join(" | ")
            );
        }
        let last = self.values.len() - 1;
        let orders: Vec<String> = (0..names.len())
            .map(|k| {
                if BANG_OBSERVABLES[k].1 == "bang_numerical_of" {
                    return self.fit[k].map_or_else(
                        || "-".to_owned(),
                        |f| {
                            if f.order_se.is_finite() {
                                format!("itself: p = {:.2} ± {:.2}", f.order, f.order_se)
                            } else {
                                format!("itself: p = {:.2}", f.order)
                            }
                        },
                    );
                }
                // The change from the finest setting is noise if within two standard errors.
                let resolved = (0..last).any(|i| {
                    let d = (self.mean[k][i] - self.mean[k][last]).abs();
                    d > 2.0 * self.se[k][i].hypot(self.se[k][last])
                });
                match (&self.fit[k], resolved) {
                    (_, false) => "within noise".to_owned(),
                    (Some(f), true) if f.order_se.is_finite() => {
                        format!("p = {:.2} ± {:.2}", f.order, f.order_se)
                    }
                    (Some(f), true) => format!("p = {:.2}", f.order),
                    (None, true) => "-".to_owned(),
                }
            })
            .collect();
        let _ = writeln!(
            o,
            "| order of the change from the finest | | {} |",
            orders.join(" | ")
        );
        o
    }
}

/// `mean ± se` with three significant digits.
fn show_mean(m: f64, se: f64) -> String {
    if !m.is_finite() {
        return "-".into();
    }
    if se.is_finite() {
        format!("{m:.3e} ± {se:.1e}")
    } else {
        format!("{m:.3e}")
    }
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
        let err = col(reference.column())?;
        let lost = col("lost_before_bang_of_e0")?;
        let links = col("links")?;
        let wall = col("wall_s")?;
        let steps = col("steps")?;
        let ok = fitting_rows(&table)
            .ok_or_else(|| anyhow::anyhow!("the sweep has no `{STATUS_COLUMN}` column"))?;
        let keys = table.varied_keys();
        let series_keys: Vec<String> = keys
            .iter()
            .filter(|k| SERIES_KEYS.contains(&k.as_str()))
            .cloned()
            .collect();
        let cell = |r: usize, k: &str| {
            let c = table.column(k).expect("a varied key is a column");
            table.rows[r][c].clone()
        };
        let series: Vec<String> = (0..table.rows.len())
            .map(|r| {
                series_keys
                    .iter()
                    .map(|k| format!("{k}={}", cell(r, k)))
                    .collect::<Vec<_>>()
                    .join(" ")
            })
            .collect();
        let only_fitting = |v: &[f64]| -> Vec<f64> {
            v.iter()
                .zip(&ok)
                .map(|(&x, &fits)| if fits { x } else { f64::NAN })
                .collect()
        };
        let front = pareto_front(&only_fitting(&cost), &only_fitting(&err));
        // Milestone errors against the exact model: t_sim = t_geo (1 + e).
        let milestone_errs: Vec<Vec<f64>> = table
            .header
            .iter()
            .filter(|h| h.starts_with("err_geo_"))
            .filter_map(|h| table.numbers(h))
            .collect();

        let mut studies = Vec::new();
        for key in keys.iter().filter(|k| !repeats.contains(k)) {
            let vals: Vec<f64> = table
                .numbers(key)
                .expect("a varied key is a column")
                .into_iter()
                .collect();
            if vals.iter().any(|v| !v.is_finite()) {
                continue; // not numeric (e.g. contact.model)
            }
            let mut groups: BTreeMap<String, Vec<usize>> = BTreeMap::new();
            for r in (0..table.rows.len()).filter(|&r| ok[r]) {
                let g = keys
                    .iter()
                    .filter(|k| *k != key && !repeats.contains(k))
                    .map(|k| format!("{k}={}", cell(r, k)))
                    .collect::<Vec<_>>()
                    .join(" ");
                groups.entry(g).or_default().push(r);
            }
            for (group, mut rows) in groups {
                rows.sort_by(|&a, &b| step_size(key, vals[b]).total_cmp(&step_size(key, vals[a])));
                let distinct = {
                    let mut v: Vec<f64> = rows.iter().map(|&r| vals[r]).collect();
                    v.sort_by(f64::total_cmp);
                    v.dedup_by(|a, b| (*a - *b).abs() <= 1e-12 * b.abs());
                    v.len()
                };
                if distinct < 2 {
                    continue;
                }
                let pick = |v: &[f64]| rows.iter().map(|&r| v[r]).collect::<Vec<f64>>();
                let h: Vec<f64> = rows.iter().map(|&r| step_size(key, vals[r])).collect();
                let e = pick(&err);
                let l = pick(&lost);
                let n = pick(&links);
                let wps: Vec<f64> = rows.iter().map(|&r| wall[r] / steps[r]).collect();
                let finest = *rows.last().expect("at least two rows");
                let self_err: Vec<f64> = rows
                    .iter()
                    .map(|&r| {
                        if r == finest {
                            return f64::NAN;
                        }
                        milestone_errs
                            .iter()
                            .map(|m| ((1.0 + m[r]) / (1.0 + m[finest]) - 1.0).abs())
                            .fold(0.0_f64, |a, d| if d.is_nan() { f64::NAN } else { a.max(d) })
                    })
                    .collect();
                studies.push(Study {
                    key: key.clone(),
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
                });
            }
        }
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
            front,
            studies,
            target: None,
        })
    }

    /// The runs left out of the fits, the front and the target, with their status (empty
    /// when every run counts).
    fn left_out(&self) -> String {
        let t = &self.table;
        let (Some(status), Some(index)) = (t.column(STATUS_COLUMN), t.column("index")) else {
            return String::new();
        };
        let keys = t.varied_keys();
        let mut o = String::new();
        for r in (0..t.rows.len()).filter(|&r| !self.fits[r]) {
            if o.is_empty() {
                o.push_str(
                    "Left out of the fits, the front and the target (failed, interrupted or \
                     stopped by a guard):\n\n",
                );
            }
            let settings: Vec<String> = keys
                .iter()
                .filter_map(|k| t.column(k).map(|c| format!("{k}={}", t.rows[r][c])))
                .collect();
            let _ = writeln!(
                o,
                "- #{} {}: {}",
                t.rows[r][index],
                settings.join(" "),
                t.rows[r][status]
            );
        }
        if !o.is_empty() {
            o.push('\n');
        }
        o
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

    /// The approach to the bang, run by run, if the sweep has its columns: the peak
    /// contact-line speed, the equivalent radius there, and the coil's outer radius where
    /// it lifted off the floor, where its speed left the exact model's by 5 %, and where the
    /// exact model itself needs a floor that pulls.
    fn approach_table(&self) -> Option<String> {
        let t = &self.table;
        let cols = [
            "peak_xdot_m_s",
            "peak_r_m",
            "lift_off_r_m",
            "leaves_exact_r_m",
            "exact_hops_r_m",
        ];
        let v: Vec<Vec<f64>> = cols.iter().map(|c| t.numbers(c)).collect::<Option<_>>()?;
        let keys = t.varied_keys();
        let mut o = String::new();
        let _ = writeln!(o, "## The approach to the bang\n");
        let _ = writeln!(
            o,
            "Peak contact-line speed x' while the coil rolls and the equivalent radius \
             r = R sqrt(1 - f) there; the coil's outer radius where it lifts off the floor \
             (no upward force for 20 steps), where x' leaves the exact-geometry model's by \
             more than 5 % (20 steps), and where the exact model needs a floor that pulls.\n"
        );
        let _ = writeln!(
            o,
            "| {} | peak x' m/s | r at peak mm | lift-off mm | leaves exact mm | exact hops mm |",
            keys.join(" | ")
        );
        let _ = writeln!(o, "|{}---|---|---|---|---|", "---|".repeat(keys.len()));
        let mm = |x: f64| {
            if x.is_finite() {
                format!("{:.2}", 1e3 * x)
            } else {
                "-".into()
            }
        };
        for (r, peak) in v[0].iter().enumerate() {
            let _ = writeln!(
                o,
                "| {} | {:.2} | {} | {} | {} | {} |",
                settings_cells(t, &keys, r),
                peak,
                mm(v[1][r]),
                mm(v[2][r]),
                mm(v[3][r]),
                mm(v[4][r])
            );
        }
        let _ = writeln!(o);
        Some(o)
    }

    /// The Markdown report: the fits, the Pareto front and every run.
    pub fn markdown(&self, title: &str) -> String {
        let t = &self.table;
        let keys = t.varied_keys();
        let mut o = String::new();
        let _ = writeln!(o, "# {title}\n");
        let _ = writeln!(
            o,
            "Error: the largest |time error| over the milestones (0.75R, 0.5R, 0.25R, 0.1R, 2b) \
             against the {}. Cost: `{}` (wall time of the engine steps{}).\n",
            self.reference.label(),
            self.cost_column,
            if self.cost_column == "wall_rolling_s" {
                " up to the final bang, i.e. the whole unroll"
            } else {
                ", final bang included"
            }
        );
        o.push_str(&self.left_out());
        if !self.studies.is_empty() {
            let _ = writeln!(o, "## Convergence\n");
            let _ = writeln!(
                o,
                "Least-squares fit of log10 y = p log10 h + c over the runs of one varied key, \
                 the others held; h is the step the key stands for (the value for a key in s or \
                 m, else 1/value). p = order ± its standard error, R² of the log-log line, n runs. Error: against the \
                 reference above; self-convergence: the largest relative change of a milestone \
                 time from the finest run of the same line (biased high next to it); energy \
                 loss: lost before the bang over E0 (the exact model loses nothing).\n"
            );
            let _ = writeln!(
                o,
                "| key | others | h range | error order p (R², n) | self-convergence order p (R², n) | energy-loss order p (R², n) | per-step cost slope vs links (R², n) |"
            );
            let _ = writeln!(o, "|---|---|---|---|---|---|---|");
            let fit = |f: &Option<PowerFit>| {
                f.map_or_else(
                    || "-".to_owned(),
                    |f| {
                        let se = if f.order_se.is_finite() {
                            format!(" ± {:.2}", f.order_se)
                        } else {
                            String::new()
                        };
                        format!("{:.2}{se} ({:.3}, {})", f.order, f.r2, f.n)
                    },
                )
            };
            for s in &self.studies {
                let (lo, hi) =
                    s.h.iter()
                        .fold((f64::INFINITY, 0.0_f64), |(a, b), &h| (a.min(h), b.max(h)));
                let _ = writeln!(
                    o,
                    "| `{}` | {} | {:.3e} .. {:.3e} | {} | {} | {} | {} |",
                    s.key,
                    if s.group.is_empty() { "-" } else { &s.group },
                    lo,
                    hi,
                    fit(&s.err_fit),
                    fit(&s.self_fit),
                    fit(&s.lost_fit),
                    fit(&s.cost_fit)
                );
            }
            let _ = writeln!(o);
        }
        if !self.bang.is_empty() {
            let _ = writeln!(o, "## The final bang\n");
            let _ = writeln!(
                o,
                "The bang is chaotic: runs whose settings differ by a fraction of a percent \
                 end differently. Each setting is an ensemble (the repetitions), each cell the mean \
                 ± the standard error of the mean. The last row fits |mean - the finest \
                 setting's mean| against the step h by least squares in log-log, where that \
                 change exceeds two standard errors somewhere (else: within noise); the \
                 numerical share, which an exact solver would make zero, is fitted itself.\n"
            );
            for b in &self.bang {
                let _ = writeln!(o, "{}", b.markdown());
            }
        }
        if let Some(text) = self.approach_table() {
            o.push_str(&text);
        }
        let _ = writeln!(o, "## Pareto front (error against cost)\n");
        if self.front.is_empty() {
            let _ = writeln!(o, "No run reached every milestone.\n");
        } else {
            let _ = writeln!(o, "| {} | cost s | error |", keys.join(" | "));
            let _ = writeln!(o, "|{}---|---|", "---|".repeat(keys.len()));
            for &r in &self.front {
                let _ = writeln!(
                    o,
                    "| {} | {:.4} | {:.3}% |",
                    settings_cells(t, &keys, r),
                    self.cost[r],
                    100.0 * self.err[r]
                );
            }
            let _ = writeln!(o);
        }
        if let Some((e, c)) = self.target {
            let ok = self.meeting_target();
            let _ = write!(
                o,
                "Target: error <= {:.3}% in <= {c} s: met by {} of {} runs",
                100.0 * e,
                ok.len(),
                t.rows.len()
            );
            match ok.first() {
                Some(&r) => {
                    let _ = writeln!(
                        o,
                        "; the cheapest: {} ({:.4} s, {:.3}%).\n",
                        keys.iter()
                            .map(|k| format!(
                                "{k}={}",
                                t.rows[r][t.column(k).expect("a varied key")]
                            ))
                            .collect::<Vec<_>>()
                            .join(" "),
                        self.cost[r],
                        100.0 * self.err[r]
                    );
                }
                None => {
                    let _ = writeln!(o, ".\n");
                }
            }
        }
        let _ = writeln!(o, "## All runs\n");
        let _ = writeln!(
            o,
            "| # | {} | links | steps | wall to bang s | wall s | wall s per sim s | err vs exact | err vs eq. 7 | lost before bang (of E0) | status |",
            keys.join(" | ")
        );
        let _ = writeln!(
            o,
            "|---|{}---|---|---|---|---|---|---|---|---|",
            "---|".repeat(keys.len())
        );
        let get = |name: &str| {
            t.numbers(name)
                .unwrap_or_else(|| vec![f64::NAN; t.rows.len()])
        };
        let links = get("links");
        let steps = get("steps");
        let wr = get("wall_rolling_s");
        let w = get("wall_s");
        let sim = get("sim_time_s");
        let eg = get("max_err_geo");
        let e7 = get("max_err_eq7");
        let lost = get("lost_before_bang_of_e0");
        let sc = t.column(STATUS_COLUMN).expect("checked in new");
        let ic = t.column("index").unwrap_or(0);
        let pc = |v: f64| {
            if v.is_finite() {
                format!("{:.3}%", 100.0 * v)
            } else {
                "-".into()
            }
        };
        for r in 0..t.rows.len() {
            let _ = writeln!(
                o,
                "| {}{} | {} | {} | {} | {:.4} | {:.4} | {:.4} | {} | {} | {} | {} |",
                t.rows[r][ic],
                if self.front.contains(&r) { " *" } else { "" },
                settings_cells(t, &keys, r),
                links[r],
                steps[r],
                wr[r],
                w[r],
                w[r] / sim[r],
                pc(eg[r]),
                pc(e7[r]),
                pc(lost[r]),
                t.rows[r][sc]
            );
        }
        let _ = writeln!(o, "\n`*`: on the Pareto front.");
        o
    }
}

fn settings_cells(t: &SweepTable, keys: &[String], r: usize) -> String {
    keys.iter()
        .map(|k| t.rows[r][t.column(k).expect("a varied key is a column")].clone())
        .collect::<Vec<_>>()
        .join(" | ")
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn fit_recovers_a_power_law() {
        // Synthetic convergence data: err = 0.3 h^1.7, exact, and with +-5% noise.
        let h: Vec<f64> = [1.0 / 8.0, 1.0 / 16.0, 1.0 / 32.0, 1.0 / 64.0].to_vec();
        let e: Vec<f64> = h.iter().map(|h| 0.3 * h.powf(1.7)).collect();
        let f = fit_power(&h, &e).unwrap();
        assert_relative_eq!(f.order, 1.7, epsilon = 1e-12);
        assert_relative_eq!(f.eval(1.0), 0.3, epsilon = 1e-12);
        assert_relative_eq!(f.r2, 1.0, epsilon = 1e-12);
        assert_eq!(f.n, 4);
        let noisy: Vec<f64> = e
            .iter()
            .zip([1.05, 0.95, 1.05, 0.95])
            .map(|(e, k)| e * k)
            .collect();
        let f = fit_power(&h, &noisy).unwrap();
        assert!(
            (f.order - 1.7).abs() < 0.1,
            "order {:.3}, expected ~1.7",
            f.order
        );
        assert!(f.r2 < 1.0 && f.r2 > 0.99, "R² {}", f.r2);
        assert!(
            f.order_se > 0.0 && f.order_se < 0.1,
            "standard error {}",
            f.order_se
        );
    }

    #[test]
    fn fit_skips_unusable_points() {
        let h = [0.1, 0.05, f64::NAN, 0.01, 0.02];
        let e = [1e-2, 2.5e-3, 1.0, 0.0, 4e-4];
        let f = fit_power(&h, &e).unwrap();
        assert_eq!(f.n, 3);
        assert_relative_eq!(f.order, 2.0, epsilon = 1e-9);
        assert!(fit_power(&[0.1, 0.1], &[1.0, 2.0]).is_none());
        // Equal up to rounding (704 links computed two ways) is still equal.
        assert!(fit_power(&[704.0, 704.0 * (1.0 + 1e-15), 704.0], &[1.0, 2.0, 3.0]).is_none());
        assert!(fit_power(&[0.1], &[1.0]).is_none());
    }

    #[test]
    fn step_size_follows_the_unit() {
        assert!((step_size("solver.bang_step_rad", 0.15) - 0.15).abs() < 1e-15);
        assert_relative_eq!(step_size("solver.max_dt_s", 1e-3), 1e-3);
        assert_relative_eq!(step_size("discretisation.links_per_turn", 32.0), 1.0 / 32.0);
        assert_relative_eq!(step_size("solver.steps_per_link", 4.0), 0.25);
    }

    #[test]
    fn pareto_front_keeps_the_undominated() {
        let cost = [1.0, 2.0, 3.0, 0.5, 2.5, f64::NAN];
        let err = [0.1, 0.2, 0.01, 0.5, 0.05, 0.0];
        assert_eq!(pareto_front(&cost, &err), vec![3, 0, 4, 2]);
    }

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
}
