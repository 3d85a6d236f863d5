//! A sweep's pictures from its [`SweepAnalysis`]: the Pareto plot, one convergence plot
//! per varied key and one picture per bang study. It draws what the analysis worked out
//! and computes nothing new.

use std::path::{Path, PathBuf};

use anyhow::Context as _;
use plotters::prelude::*;

use super::{
    Area, DESC_PX, Drawn, EXACT, HouseStyle, Line, LogChart, LogTicks, SIM, X_LABEL_AREA_PX,
    X_TICK_ROOM_PX, Y_LABEL_AREA_PX, color, draw_line, draw_markers, err, font, legend, log_chart,
    log_range, pairs, plot_size, positive_pairs, range,
};
use crate::study::analysis::{BANG_OBSERVABLES, BangStudy, PowerFit, Study, SweepAnalysis};

/// `p ± se` of a fit.
fn order(f: &PowerFit) -> String {
    if f.order_se.is_finite() {
        format!("{:.2} ± {:.2}", f.order, f.order_se)
    } else {
        format!("{:.2}", f.order)
    }
}

/// Draws a fitted power law over `[h0, h1]` and names its order in the legend; books it in
/// `drawn`.
fn fit_line(
    chart: &mut LogChart<'_, '_>,
    drawn: &mut Drawn,
    fit: &PowerFit,
    h: &[f64],
    label: String,
    c: RGBColor,
) -> anyhow::Result<()> {
    let (lo, hi) = h
        .iter()
        .filter(|v| v.is_finite() && **v > 0.0)
        .fold((f64::INFINITY, 0.0_f64), |(a, b), &v| (a.min(v), b.max(v)));
    if !lo.is_finite() {
        return Ok(());
    }
    draw_line(
        chart,
        drawn,
        vec![(lo, fit.eval(lo)), (hi, fit.eval(hi))],
        Line::dashed(c, 1, 6, 4),
        label,
    )
}

/// Draws a sweep's pictures into `dir`: `pareto.svg` (error against cost, log-log, one
/// series per contact model / solver setting, the front joined) and, per varied numeric
/// key, `convergence-<key>.svg` (error and energy lost before the bang against the step
/// size with the fitted orders, and the wall time per step against links). Returns the
/// files written.
pub fn plot_sweep(a: &SweepAnalysis, dir: &Path, title: &str) -> anyhow::Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir)
        .with_context(|| format!("cannot create output folder {}", dir.display()))?;
    let mut written = Vec::new();
    // One setting's repetitions are no front to choose from.
    if !a.one_setting() {
        let pareto = dir.join("pareto.svg");
        pareto_plot(&pareto, a, title)?;
        written.push(pareto);
    }
    let mut keys: Vec<&String> = a.studies.iter().map(|s| &s.key).collect();
    keys.dedup();
    for key in keys {
        let path = dir.join(format!("convergence-{key}.svg"));
        convergence_plot(&path, a, key, title)?;
        written.push(path.clone());
    }
    written.extend(bang_plots(a, dir, title)?);
    Ok(written)
}

/// `path`: error against cost, log-log, one series per contact model / solver setting,
/// the front joined, and the target's box if there is one.
fn pareto_plot(path: &Path, a: &SweepAnalysis, title: &str) -> anyhow::Result<()> {
    let root = SVGBackend::new(path, (900, 600)).into_drawing_area();
    root.fill(&WHITE).map_err(err)?;
    let idx: Vec<usize> = (0..a.cost.len())
        .filter(|&i| a.cost[i].is_finite() && a.err[i].is_finite() && a.err[i] > 0.0)
        .collect();
    let mut chart = log_chart(
        &root,
        &format!("{title}: error against wall time"),
        &format!("wall time, {} (s)", a.cost_column),
        &format!("max |time error| vs {}", a.reference.label()),
        idx.iter().map(|&i| a.cost[i]).chain(a.target.map(|t| t.1)),
        idx.iter().map(|&i| a.err[i]).chain(a.target.map(|t| t.0)),
    )?;
    let mut names: Vec<&String> = idx.iter().map(|&i| &a.series[i]).collect();
    names.sort();
    names.dedup();
    let mut drawn = Drawn::default();
    for (si, name) in names.iter().enumerate() {
        let c = color(si);
        let pts: Vec<(f64, f64)> = idx
            .iter()
            .filter(|&&i| &&a.series[i] == name)
            .map(|&i| (a.cost[i], a.err[i]))
            .collect();
        let label = if name.is_empty() {
            "runs".to_owned()
        } else {
            (*name).clone()
        };
        draw_markers(&mut chart, &mut drawn, &pts, c.filled(), label)?;
    }
    let front: Vec<(f64, f64)> = a
        .front
        .iter()
        .filter(|&&i| a.setting_err[i] > 0.0)
        .map(|&i| (a.setting_cost[i], a.setting_err[i]))
        .collect();
    // Each setting on the front ringed (at its runs' means), so that a front of one shows too.
    drawn.book(&chart, &front, true, "on the Pareto front".to_owned());
    let ring = BLACK.stroke_width(1);
    chart
        .draw_series(front.iter().map(|&p| Circle::new(p, 8, ring)))
        .map_err(err)?
        .label("on the Pareto front")
        .legend(move |(x, y)| Circle::new((x + 10, y), 8, ring));
    let line = Line::solid(BLACK, 1);
    draw_line(&mut chart, &mut drawn, front, line, "Pareto front")?;
    if let Some((e, c)) = a.target {
        let (x0, _) = log_range(idx.iter().map(|&i| a.cost[i]).chain([c]));
        let (y0, _) = log_range(idx.iter().map(|&i| a.err[i]).chain([e]));
        let grey = RGBColor(127, 127, 127);
        draw_line(
            &mut chart,
            &mut drawn,
            vec![(x0, e), (c, e), (c, y0)],
            Line::dashed(grey, 2, 6, 4),
            format!("target: <= {:.2}% in <= {c} s", 100.0 * e),
        )?;
    }
    legend(&mut chart, &drawn)?;
    root.present().map_err(err)?;
    Ok(())
}

/// What the upper panels of a convergence plot show against the step size.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Measure {
    /// The error, with the change from the finest run (self-convergence).
    Error,
    /// The energy lost before the bang over E0.
    Lost,
}

/// `path`: the studies of `key`: their error and their energy lost before the bang against
/// the step size with the fitted orders, and their wall time per step against links.
fn convergence_plot(path: &Path, a: &SweepAnalysis, key: &str, title: &str) -> anyhow::Result<()> {
    let studies: Vec<&Study> = a.studies.iter().filter(|s| s.key == key).collect();
    let root = SVGBackend::new(path, (900, 1200)).into_drawing_area();
    root.fill(&WHITE).map_err(err)?;
    let panels = root.split_evenly((3, 1));
    let h_desc = format!("step h of {key} (1/value unless the key is in s or m)");
    for (panel, measure) in panels.iter().take(2).zip([Measure::Error, Measure::Lost]) {
        step_panel(panel, a, &studies, measure, &h_desc, title)?;
    }
    cost_panel(&panels[2], &studies, title)?;
    root.present().map_err(err)?;
    Ok(())
}

/// One upper panel of a convergence plot: `measure` against the step size, a series and
/// its fit per study.
fn step_panel(
    panel: &Area<'_>,
    a: &SweepAnalysis,
    studies: &[&Study],
    measure: Measure,
    h_desc: &str,
    title: &str,
) -> anyhow::Result<()> {
    let error = measure == Measure::Error;
    let (ys, fits): (Vec<&Vec<f64>>, Vec<Option<PowerFit>>) = studies
        .iter()
        .map(|s| {
            if error {
                (&s.err, s.err_fit)
            } else {
                (&s.lost, s.lost_fit)
            }
        })
        .unzip();
    let caption = if error {
        format!("{title}: max |time error| vs {}", a.reference.label())
    } else {
        format!("{title}: energy lost before the bang")
    };
    let mut chart = log_chart(
        panel,
        &caption,
        h_desc,
        if error { "error" } else { "lost / E0" },
        studies.iter().flat_map(|s| s.h.iter().copied()),
        ys.iter().flat_map(|y| y.iter().copied()).chain(
            studies
                .iter()
                .filter(|_| error)
                .flat_map(|s| s.self_err.iter().copied()),
        ),
    )?;
    let mut drawn = Drawn::default();
    for (si, (s, (y, fit))) in studies.iter().zip(ys.iter().zip(&fits)).enumerate() {
        let c = color(si);
        let pts = positive_pairs(&s.h, y);
        let group = if s.group.is_empty() || studies.len() == 1 {
            String::new()
        } else {
            format!("{}: ", s.group)
        };
        let label = format!("{group}runs");
        draw_markers(&mut chart, &mut drawn, &pts, c.filled(), label)?;
        if let Some(f) = fit {
            fit_line(
                &mut chart,
                &mut drawn,
                f,
                &s.h,
                format!("{group}fit: order {} (R² {:.3})", order(f), f.r2),
                c,
            )?;
        }
        if error {
            self_convergence(&mut chart, &mut drawn, s, &group, c)?;
        }
    }
    legend(&mut chart, &drawn)?;
    Ok(())
}

/// A study's change from its finest run against the step size (open circles), with its
/// fit, in colour `c`; `group` prefixes the labels; booked in `drawn`.
fn self_convergence(
    chart: &mut LogChart<'_, '_>,
    drawn: &mut Drawn,
    s: &Study,
    group: &str,
    c: RGBColor,
) -> anyhow::Result<()> {
    let pts = positive_pairs(&s.h, &s.self_err);
    let label = format!("{group}change from the finest run");
    draw_markers(chart, drawn, &pts, c.stroke_width(1), label)?;
    if let Some(f) = &s.self_fit {
        fit_line(
            chart,
            drawn,
            f,
            &s.h,
            format!(
                "{group}self-convergence: order {} (R² {:.3})",
                order(f),
                f.r2
            ),
            c,
        )?;
    }
    Ok(())
}

/// The lower panel of a convergence plot: wall time per step against links, with the
/// fitted slope, per study.
fn cost_panel(panel: &Area<'_>, studies: &[&Study], title: &str) -> anyhow::Result<()> {
    let mut chart = log_chart(
        panel,
        &format!("{title}: wall time per step against links"),
        "links",
        "wall time per step (s)",
        studies.iter().flat_map(|s| s.links.iter().copied()),
        studies
            .iter()
            .flat_map(|s| s.wall_per_step_s.iter().copied()),
    )?;
    let mut drawn = Drawn::default();
    for (si, s) in studies.iter().enumerate() {
        let c = color(si);
        let pts = pairs(&s.links, &s.wall_per_step_s);
        let label = if s.group.is_empty() || studies.len() == 1 {
            "runs".to_owned()
        } else {
            s.group.clone()
        };
        draw_markers(&mut chart, &mut drawn, &pts, c.filled(), label)?;
        if let Some(f) = &s.cost_fit {
            fit_line(
                &mut chart,
                &mut drawn,
                f,
                &s.links,
                format!("slope {} (R² {:.3})", order(f), f.r2),
                c,
            )?;
        }
    }
    legend(&mut chart, &drawn)?;
    Ok(())
}

/// The final bang's ensembles: one picture per study, `bang-<key>.svg`, or
/// `bang-<key>-<i>.svg` where the key has several groups. Returns the files written.
fn bang_plots(a: &SweepAnalysis, dir: &Path, title: &str) -> anyhow::Result<Vec<PathBuf>> {
    let mut written = Vec::new();
    // A physical key: the shares against its values, one line per setting of the others.
    let mut physical: Vec<&str> = a
        .bang
        .iter()
        .filter(|b| b.physical && !b.pooled)
        .map(|b| b.key.as_str())
        .collect();
    physical.dedup();
    for key in physical {
        let studies: Vec<&BangStudy> = a.bang.iter().filter(|b| b.key == key).collect();
        let path = dir.join(format!("shares-{key}.svg"));
        super::shares::shares_plot(&path, key, &studies, title)?;
        written.push(path);
    }
    let keys: Vec<&str> = a.bang.iter().map(|b| b.key.as_str()).collect();
    for (i, b) in a
        .bang
        .iter()
        .enumerate()
        .filter(|(_, b)| !b.physical && !b.pooled)
    {
        let alone = keys.iter().filter(|k| **k == b.key).count() == 1;
        let stem = if alone {
            format!("bang-{}", b.key)
        } else {
            format!("bang-{}-{i}", b.key)
        };
        let path = dir.join(format!("{stem}.svg"));
        bang_study_plot(&path, b, title)?;
        written.push(path);
        let path = dir.join(format!("pareto-{stem}.svg"));
        bang_pareto_plot(&path, b, title)?;
        written.push(path);
    }
    Ok(written)
}

/// `path`: the bang's speed against its error in one study, log-log: each setting's
/// numerical share (its size, ± its standard error) against its bang engine time, each
/// named by its value and its runs (those that ran to their end), the front joined.
fn bang_pareto_plot(path: &Path, b: &BangStudy, title: &str) -> anyhow::Result<()> {
    let root = SVGBackend::new(path, (900, 600)).into_drawing_area();
    root.fill(&WHITE).map_err(err)?;
    let points = b.speed_and_error();
    let shown: Vec<usize> = (0..points.len())
        .filter(|&i| points[i][0] > 0.0 && points[i][2] > 0.0)
        .filter(|&i| points[i][0].is_finite() && points[i][2].is_finite())
        .collect();
    let group = if b.group.is_empty() {
        String::new()
    } else {
        format!(", {}", b.group)
    };
    let mut chart = log_chart(
        &root,
        &format!(
            "{title}: the bang's error against its engine time, {}{group}",
            b.key
        ),
        "bang wall time (s), mean of the ensemble",
        "|numerical share| of what the bang dissipated",
        shown.iter().map(|&i| points[i][0]),
        shown
            .iter()
            .flat_map(|&i| [points[i][2], points[i][2] + points[i][3].max(0.0)]),
    )?;
    let mut drawn = Drawn::default();
    // The bars: mean ± standard error, the lower end kept on the log axis.
    chart
        .draw_series(shown.iter().map(|&i| {
            let [c, _, e, se] = points[i];
            let se = if se.is_finite() { se } else { 0.0 };
            ErrorBar::new_vertical(c, (e - se).max(e / 10.0), e, e + se, SIM.filled(), 6)
        }))
        .map_err(err)?;
    let pts: Vec<(f64, f64)> = shown
        .iter()
        .map(|&i| (points[i][0], points[i][2]))
        .collect();
    draw_markers(
        &mut chart,
        &mut drawn,
        &pts,
        SIM.filled(),
        format!("a setting of {} (mean ± standard error)", b.key),
    )?;
    chart
        .draw_series(shown.iter().map(|&i| {
            Text::new(
                format!("{} ({} runs)", b.values[i], b.n[i]),
                (points[i][0], points[i][2]),
                font(DESC_PX),
            )
        }))
        .map_err(err)?;
    let front: Vec<(f64, f64)> = b
        .front()
        .into_iter()
        .filter(|i| shown.contains(i))
        .map(|i| (points[i][0], points[i][2]))
        .collect();
    draw_line(
        &mut chart,
        &mut drawn,
        front,
        Line::solid(BLACK, 1),
        "Pareto front",
    )?;
    legend(&mut chart, &drawn)?;
    root.present().map_err(err)?;
    Ok(())
}

/// One panel per bang observable: its ensemble mean ± standard error against the step h
/// of the study's key (log h).
fn bang_study_plot(path: &Path, b: &BangStudy, title: &str) -> anyhow::Result<()> {
    let root = SVGBackend::new(path, (1000, 1650)).into_drawing_area();
    root.fill(&WHITE).map_err(err)?;
    let (head, body) = root.split_vertically(40);
    head.draw(&Text::new(
        format!(
            "{title}: the final bang against {}{} (ensemble mean ± standard error)",
            b.key,
            if b.group.is_empty() {
                String::new()
            } else {
                format!(", {}", b.group)
            }
        ),
        (20, 12),
        font(DESC_PX),
    ))
    .map_err(err)?;
    let panels = body.split_evenly((6, 2));
    let (h0, h1) = log_range(b.h.iter().copied());
    for (k, panel) in panels.iter().enumerate().take(BANG_OBSERVABLES.len()) {
        let (m, se) = (&b.mean[k], &b.se[k]);
        let lo = m.iter().zip(se).map(|(m, s)| m - s.max(0.0));
        let hi = m.iter().zip(se).map(|(m, s)| m + s.max(0.0));
        let (y0, y1) = range(lo.chain(hi));
        let ticks = LogTicks::new((h0, h1), plot_size(panel, true).0, X_TICK_ROOM_PX);
        let mut chart = ChartBuilder::on(panel)
            .caption(BANG_OBSERVABLES[k].0, font(DESC_PX))
            .margin(8)
            .x_label_area_size(X_LABEL_AREA_PX)
            .y_label_area_size(Y_LABEL_AREA_PX)
            .build_cartesian_2d(ticks.axis((h0, h1)), y0..y1)
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc(format!("h of {}", b.key))
            // A panel is some 160 px high: six labels leave room between them.
            .y_labels(6)
            .x_labels(ticks.values.len().max(1))
            .x_label_formatter(&LogTicks::label)
            .house_style()
            .draw()
            .map_err(err)?;
        let pts = pairs(&b.h, m);
        chart
            .draw_series(LineSeries::new(pts.iter().copied(), SIM.stroke_width(1)))
            .map_err(err)?;
        chart
            .draw_series(
                b.h.iter()
                    .zip(m)
                    .zip(se)
                    .filter(|((h, m), s)| h.is_finite() && m.is_finite() && s.is_finite())
                    .map(|((&h, &m), &s)| {
                        ErrorBar::new_vertical(h, m - s, m, m + s, EXACT.filled(), 6)
                    }),
            )
            .map_err(err)?;
    }
    root.present().map_err(err)?;
    Ok(())
}
