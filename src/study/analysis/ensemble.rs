//! One setting's ensemble of landings pooled (`uncoil run SCENE --ensemble N`): the
//! milestones' simulated times as their mean and spread (the unrolls hardly differ), and
//! every observable of the final bang as its mean and the standard error of that mean (a
//! landing is chaotic), the figures of [`BangStudy::pooled`](super::BangStudy::pooled).
//! Numbers and text only: it reads a sweep's table.

use std::fmt::Write as _;

use super::bang::{mean_and_se, observed};
use super::report::sci;
use super::{BANG_OBSERVABLES, NUMERICAL, fitting_rows};
use crate::study::sweep::{Col, SweepTable, T_SIM_PREFIX, csv_line};

/// One quantity over the runs it counts.
#[derive(Debug, Clone, PartialEq)]
pub struct Pooled {
    /// Its name, as the summary prints it.
    pub label: String,
    /// Its unit (`1` for a share or a ratio).
    pub unit: &'static str,
    /// The runs it counts.
    pub n: usize,
    /// Their mean.
    pub mean: f64,
    /// Their sample standard deviation (`NaN` with one run).
    pub sd: f64,
    /// The standard error of the mean, `sd / sqrt(n)`.
    pub se: f64,
    /// The least value.
    pub min: f64,
    /// The greatest value.
    pub max: f64,
}

impl Pooled {
    /// `values` pooled where finite.
    fn of(label: String, unit: &'static str, values: impl Iterator<Item = f64>) -> Self {
        let v: Vec<f64> = values.filter(|x| x.is_finite()).collect();
        let (mean, se) = mean_and_se(v.iter().copied());
        let n = v.len();
        Self {
            label,
            unit,
            n,
            mean,
            sd: se * (n as f64).sqrt(),
            se,
            min: v.iter().copied().fold(f64::INFINITY, f64::min),
            max: v.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        }
    }
}

/// A sweep of one setting's repetitions, pooled.
#[derive(Debug, Clone, PartialEq)]
pub struct Ensemble {
    /// Rows in the sweep.
    pub runs: usize,
    /// Runs that ran to their end (status `ok` or `max_time`): the milestones' runs.
    pub counted: usize,
    /// Runs whose bang counts (they fit, and their bang took time): the bang's runs.
    pub landed: usize,
    /// Each milestone's simulated time (`t_sim_<label>`), then the release and the end of
    /// the bang (s).
    pub milestones: Vec<Pooled>,
    /// Each of [`BANG_OBSERVABLES`], in its order.
    pub bang: Vec<Pooled>,
}

impl Ensemble {
    /// Pools every row of `table` as one setting.
    pub fn new(table: &SweepTable) -> Self {
        let rows = table.rows.len();
        let fits = fitting_rows(table).unwrap_or_else(|| vec![true; rows]);
        let counted = |v: Vec<f64>| v.into_iter().zip(&fits).filter(|(_, f)| **f).map(|x| x.0);
        let mut milestones = Vec::new();
        for name in table.header.iter().filter(|h| h.starts_with(T_SIM_PREFIX)) {
            let label = name[T_SIM_PREFIX.len()..].to_owned();
            let t = table.numbers(name).expect("a column of the header");
            milestones.push(Pooled::of(label, "s", counted(t)));
        }
        // In the order the runs reach them (2b before 0.1R on a coil of twelve turns).
        milestones.sort_by(|a, b| a.mean.total_cmp(&b.mean));
        let nan = vec![f64::NAN; rows];
        let release = table.col(Col::BangTime).unwrap_or_else(|| nan.clone());
        let duration = table.col(Col::BangDuration).unwrap_or(nan);
        let rest: Vec<f64> = release.iter().zip(&duration).map(|(a, b)| a + b).collect();
        milestones.push(Pooled::of("release".into(), "s", counted(release)));
        milestones.push(Pooled::of("bang ends".into(), "s", counted(rest)));
        let (bang, landed) = match observed(table) {
            Some((values, landed)) => {
                let bang = BANG_OBSERVABLES
                    .iter()
                    .zip(values)
                    .map(|((label, _), v)| {
                        let unit = label
                            .rfind('(')
                            .map_or("1", |k| unit_of(&label[k + 1..label.len() - 1]));
                        let mine = v.into_iter().zip(&landed).filter(|(_, l)| **l).map(|x| x.0);
                        Pooled::of((*label).to_owned(), unit, mine)
                    })
                    .collect();
                (bang, landed.iter().filter(|l| **l).count())
            }
            None => (Vec::new(), 0),
        };
        Self {
            runs: rows,
            counted: fits.iter().filter(|f| **f).count(),
            landed,
            milestones,
            bang,
        }
    }

    /// `ensemble.csv`: one row per quantity (`quantity,unit,runs,mean,sd,se,min,max`), the
    /// milestones' times then the bang's observables; a share is a fraction of what the bang
    /// dissipated.
    pub fn csv(&self) -> String {
        let mut o = csv_line(
            &["quantity", "unit", "runs", "mean", "sd", "se", "min", "max"].map(String::from),
        ) + "\n";
        let num = |x: f64| {
            if x.is_finite() {
                format!("{x:.9e}")
            } else {
                String::new()
            }
        };
        for (prefix, list) in [("t ", &self.milestones), ("", &self.bang)] {
            for p in list {
                let cells = [
                    format!("{prefix}{}", p.label),
                    p.unit.to_owned(),
                    p.n.to_string(),
                    num(p.mean),
                    num(p.sd),
                    num(p.se),
                    num(p.min),
                    num(p.max),
                ];
                o.push_str(&csv_line(&cells));
                o.push('\n');
            }
        }
        o
    }

    /// The summary `uncoil run SCENE --ensemble N` prints: the pushes from `first` to
    /// `last` (m/s); the milestones as mean ± standard deviation (the spread of the runs),
    /// the bang as mean ± standard error of the mean, each saying over how many runs.
    pub fn summary(&self, first: &str, last: &str) -> String {
        let mut o = String::new();
        let _ = writeln!(
            o,
            "{} of {} runs (pushes {first}..{last} m/s) ran to their end. Simulated time to \
             each milestone they reached, the mean ± the standard deviation of the runs (their \
             spread), and their least and greatest:",
            self.counted, self.runs
        );
        for p in self.milestones.iter().filter(|p| p.n > 0) {
            let _ = writeln!(
                o,
                "  {:<10} {:>9.4} ± {:.4} s   ({:.4}..{:.4})",
                p.label, p.mean, p.sd, p.min, p.max
            );
        }
        if self.landed < 2 {
            let _ = writeln!(
                o,
                "{} landed: an ensemble's mean and error need two",
                self.landed
            );
            return o;
        }
        let _ = writeln!(
            o,
            "The final bang over {} landings: each figure the mean ± the standard error of the \
             mean; shares of what the bang dissipated:",
            self.landed
        );
        for (p, (_, reading)) in self.bang.iter().zip(BANG_OBSERVABLES) {
            let text = if p.label.ends_with("share") {
                let digits = if reading == NUMERICAL { 3 } else { 1 };
                format!("{:.digits$} ± {:.digits$} %", 100.0 * p.mean, 100.0 * p.se)
            } else {
                format!("{} ± {}", sci(p.mean), sci(p.se))
            };
            let _ = writeln!(o, "  {:<28} {text}", p.label);
        }
        o
    }
}

/// The unit a label states in its parentheses, as `ensemble.csv` writes it.
fn unit_of(stated: &str) -> &'static str {
    match stated {
        "m/s" => "m/s",
        "s" => "s",
        "N" => "N",
        "N s" => "N s",
        "m" => "m",
        _ => "1",
    }
}
