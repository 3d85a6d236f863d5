//! The Markdown report of a sweep: the runs left out, the convergence table, the final
//! bang's tables, the approach to the bang, the Pareto front, the target and every run.
//! Text only: every number it shows is worked out in the analysis or read from the table.

use std::fmt::Write as _;

use super::fit::MIN_FIT_POINTS;
use super::{BANG_OBSERVABLES, BangStudy, NUMERICAL, NUMERICAL_MARK, PowerFit, SweepAnalysis};
use crate::study::sweep::{INDEX_COLUMN, STATUS_COLUMN, SweepTable};

impl BangStudy {
    /// The study as Markdown: one row per setting (mean ± standard error of each
    /// observable), then the fitted order of each observable's change from the finest
    /// setting, and whether that change is within two standard errors.
    pub fn markdown(&self) -> String {
        let mut o = String::new();
        let with = if self.tied.is_empty() {
            String::new()
        } else {
            format!(", varied together with `{}`", self.tied.join("`, `"))
        };
        let group = if self.group.is_empty() {
            String::new()
        } else {
            format!(" ({})", self.group)
        };
        let names: Vec<&str> = BANG_OBSERVABLES.iter().map(|o| o.0).collect();
        if self.pooled {
            let _ = writeln!(
                o,
                "### The ensemble: `{}` pooled\n\nEvery run is a repetition of one setting: \
                 each cell is the mean ± the standard error of the mean over the {} runs \
                 (the shares are of what the bang dissipated).\n",
                self.key, self.n[0]
            );
            let _ = writeln!(o, "| runs | {} |", names.join(" | "));
            let _ = writeln!(o, "|---|{}", "---|".repeat(names.len()));
            let cells: Vec<String> = (0..names.len())
                .map(|k| show_mean(self.mean[k][0], self.se[k][0]))
                .collect();
            let _ = writeln!(o, "| {} | {} |", self.n[0], cells.join(" | "));
            if self.numerical_marked(0) {
                let _ = writeln!(
                    o,
                    "\nThe numerical share exceeds {} % in size: the split is not the physics' \
                     alone.",
                    100.0 * NUMERICAL_MARK
                );
            }
            return o;
        }
        let _ = writeln!(o, "### `{}`{with}{group}\n", self.key);
        let _ = writeln!(o, "| {} | runs | {} |", self.key, names.join(" | "));
        let _ = writeln!(o, "|---|---|{}", "---|".repeat(names.len()));
        for i in 0..self.values.len() {
            let cells: Vec<String> = (0..names.len())
                .map(|k| show_mean(self.mean[k][i], self.se[k][i]))
                .collect();
            let _ = writeln!(
                o,
                "| {}{} | {} | {} |",
                self.values[i],
                if self.numerical_marked(i) { " (!)" } else { "" },
                self.n[i],
                cells.join(" | ")
            );
        }
        if (0..self.values.len()).any(|i| self.numerical_marked(i)) {
            let _ = writeln!(
                o,
                "\n(!): the numerical share exceeds {} % in size: the split there is not the \
                 physics' alone.",
                100.0 * NUMERICAL_MARK
            );
        }
        if self.physical {
            // A physical key's settings are the answer, not steps towards one.
            return o;
        }
        let last = self.values.len() - 1;
        let orders: Vec<String> = (0..names.len())
            .map(|k| {
                if BANG_OBSERVABLES[k].1 == NUMERICAL {
                    return self.fit[k].map_or_else(
                        || "itself: too few points to fit".to_owned(),
                        |f| format!("itself: p = {:.2} ± {:.2}", f.order, f.order_se),
                    );
                }
                // With one run a setting there is no error to tell a change from noise by.
                if self.se[k].iter().any(|s| !s.is_finite()) {
                    return "one run a setting: no error to judge by".to_owned();
                }
                // The change from the finest setting is noise if within two standard errors.
                let resolved = (0..last).any(|i| {
                    let d = (self.mean[k][i] - self.mean[k][last]).abs();
                    d > 2.0 * self.se[k][i].hypot(self.se[k][last])
                });
                match (&self.fit[k], resolved) {
                    (_, false) => "within noise".to_owned(),
                    (Some(f), true) => format!("p = {:.2} ± {:.2}", f.order, f.order_se),
                    (None, true) => "too few points to fit".to_owned(),
                }
            })
            .collect();
        let _ = writeln!(
            o,
            "| order of the change from the finest | | {} |",
            orders.join(" | ")
        );
        o.push_str(&self.front_markdown());
        o
    }

    /// The bang's speed against its error: each setting's engine time and numerical share,
    /// and whether it is on the front ([`BangStudy::front`]).
    fn front_markdown(&self) -> String {
        let mut o = String::new();
        let front = self.front();
        let _ = writeln!(
            o,
            "\nThe bang's speed against its error (`pareto-bang-{}.svg`, numbered where the key \
             has several studies): each setting's \
             bang engine time and the size of its numerical share, mean ± standard error; \
             on the front where no other setting is both faster and more accurate.\n",
            self.key
        );
        let _ = writeln!(
            o,
            "| {} | bang wall (s) | numerical share | on the front |",
            self.key
        );
        let _ = writeln!(o, "|---|---|---|---|");
        for (i, p) in self.speed_and_error().iter().enumerate() {
            let _ = writeln!(
                o,
                "| {} | {} | {} | {} |",
                self.values[i],
                show_mean(p[0], p[1]),
                show_mean(p[2], p[3]),
                if front.contains(&i) { "yes" } else { "" }
            );
        }
        o
    }
}

/// `mean ± se` with three significant digits.
/// A number in four significant figures, `-` if not finite.
pub(super) fn sci(x: f64) -> String {
    if x.is_finite() {
        format!("{x:.3e}")
    } else {
        "-".into()
    }
}

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

impl SweepAnalysis {
    /// The runs left out of the fits, the front and the target, with their status (empty
    /// when every run counts).
    fn left_out(&self) -> String {
        let t = &self.table;
        let (Some(status), Some(index)) = (t.column(STATUS_COLUMN), t.column(INDEX_COLUMN)) else {
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
        let keys = self.table.varied_keys();
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
            o.push_str(&self.convergence_table());
        }
        if !self.bang.is_empty() {
            o.push_str(&self.bang_tables());
        }
        if let Some(text) = self.approach_table() {
            o.push_str(&text);
        }
        o.push_str(&self.front_table(&keys));
        if let Some(text) = self.target_line(&keys) {
            o.push_str(&text);
        }
        o.push_str(&self.runs_table(&keys));
        o
    }

    /// The convergence section: one row per study, its step range and its four fits.
    fn convergence_table(&self) -> String {
        let mut o = String::new();
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
                show_fit(&s.err_fit),
                show_fit(&s.self_fit),
                show_fit(&s.lost_fit),
                show_fit(&s.cost_fit)
            );
        }
        let _ = writeln!(o);
        o
    }

    /// The final bang's section: what its tables show, then one table per bang study.
    fn bang_tables(&self) -> String {
        let mut o = String::new();
        let _ = writeln!(o, "## The final bang\n");
        let _ = writeln!(
            o,
            "The bang is chaotic: runs whose settings differ by a fraction of a percent \
             end differently. Each setting is an ensemble (the repetitions), each cell the mean \
             ± the standard error of the mean. The last row fits |mean - the finest \
             setting's mean| against the step h by least squares in log-log, where that \
             change exceeds two standard errors somewhere (else: within noise); the \
             numerical share, which an exact solver would make zero, is fitted itself. A \
             physical key (the tape, the floor, gravity, the push, the stop: not the \
             discretisation or the solver) is no step: its table has no such row, and its \
             shares are drawn against its own values.\n"
        );
        if !self.repeats.is_empty() {
            let _ = writeln!(
                o,
                "Pooled as the repetitions of each setting: `{}`.\n",
                self.repeats.join("`, `")
            );
        }
        for b in &self.bang {
            let _ = writeln!(o, "{}", b.markdown());
        }
        o
    }

    /// The Pareto front, by cost, with the settings of its runs.
    fn front_table(&self, keys: &[String]) -> String {
        let t = &self.table;
        let mut o = String::new();
        let _ = writeln!(o, "## Pareto front (error against cost)\n");
        if self.one_setting() {
            let _ = writeln!(
                o,
                "None: every run is a repetition of one setting (`{}`), none a setting to \
                 choose (`--repeat-key none` ranks the runs themselves).\n",
                self.repeats.join("`, `")
            );
            return o;
        }
        if self.front.is_empty() {
            let _ = writeln!(o, "No run reached every milestone.\n");
            return o;
        }
        // A repetition is no setting to choose: each setting is the mean over its runs.
        let keys: Vec<String> = keys
            .iter()
            .filter(|k| !self.repeats.contains(k))
            .cloned()
            .collect();
        if !self.repeats.is_empty() {
            let _ = writeln!(
                o,
                "Each setting's cost and error are the means over its runs (`{}` pooled).\n",
                self.repeats.join("`, `")
            );
        }
        let _ = writeln!(o, "| {} | runs | cost s | error |", keys.join(" | "));
        let _ = writeln!(o, "|{}---|---|---|", "---|".repeat(keys.len()));
        for &r in &self.front {
            let _ = writeln!(
                o,
                "| {} | {} | {:.4} | {:.3}% |",
                settings_cells(t, &keys, r),
                self.setting_runs[r],
                self.setting_cost[r],
                100.0 * self.setting_err[r]
            );
        }
        let _ = writeln!(o);
        o
    }

    /// How many runs meet the target and the cheapest of them; `None` without a target.
    fn target_line(&self, keys: &[String]) -> Option<String> {
        let (e, c) = self.target?;
        let t = &self.table;
        let mut o = String::new();
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
                        .map(|k| format!("{k}={}", t.rows[r][t.column(k).expect("a varied key")]))
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
        Some(o)
    }

    /// Every run: its settings, size, wall times, errors, energy lost and status; a `*`
    /// marks the front.
    fn runs_table(&self, keys: &[String]) -> String {
        let t = &self.table;
        let mut o = String::new();
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
        let ic = t.column(INDEX_COLUMN).unwrap_or(0);
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
                if self.front.contains(&self.setting[r]) {
                    " *"
                } else {
                    ""
                },
                settings_cells(t, keys, r),
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
        let _ = writeln!(o, "\n`*`: of a setting on the Pareto front.");
        o
    }
}

/// A fit as `p ± se (R², n)`, or why there is none.
fn show_fit(f: &Option<PowerFit>) -> String {
    f.map_or_else(
        || format!("too few points to fit (under {MIN_FIT_POINTS})"),
        |f| {
            let se = if f.order_se.is_finite() {
                format!(" ± {:.2}", f.order_se)
            } else {
                String::new()
            };
            format!("{:.2}{se} ({:.3}, {})", f.order, f.r2, f.n)
        },
    )
}

fn settings_cells(t: &SweepTable, keys: &[String], r: usize) -> String {
    keys.iter()
        .map(|k| t.rows[r][t.column(k).expect("a varied key is a column")].clone())
        .collect::<Vec<_>>()
        .join(" | ")
}

#[cfg(test)]
mod tests;
