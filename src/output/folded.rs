//! A folded chain's outputs: `samples.csv` (streamed into `.partial`, renamed when
//! complete), `report.json` (atomic), and the readable summary. The chain has no Foxglove
//! view; the folder it is written into is taken for it ([`RunFolder`]), so no older
//! `run.mcap` is left to be taken for this run's.

use std::fs::{self, File};
use std::sync::atomic::AtomicBool;

use anyhow::Context as _;
use serde::Serialize;

use crate::output::folder::{FileStamp, FolderError, REPORT, RunFolder, SAMPLES, run_id};
use crate::output::table::Table;
use crate::output::{partial_path, write_atomic};
use crate::run::folded::{CayleyReport, ChainEnd, ChainReport, ChainSample, Crossing, run_chain};
use crate::scene::folded::{ChainJoints, FoldedChain, Start};

/// What `report.json` holds for a folded chain: the scene as given and what the run found;
/// Python's run of a chain without files gets the same, less the run's id and files.
#[derive(Serialize)]
struct Written<'a> {
    kind: &'static str,
    scene: &'a FoldedChain,
    report: &'a ChainReport,
    /// The run's id and the files it was written with, as a coil's `report.json` has them.
    #[serde(skip_serializing_if = "Option::is_none")]
    run_id: Option<&'a str>,
    #[serde(skip_serializing_if = "std::collections::BTreeMap::is_empty")]
    files: std::collections::BTreeMap<&'static str, FileStamp>,
}

/// A folded chain's run as `report.json` has it (kind, scene, report), without the run's id
/// and files: what Python's `uncoil.run` gives for a chain run without an output folder.
pub fn chain_report_json(scene: &FoldedChain, report: &ChainReport) -> anyhow::Result<String> {
    let written = Written {
        kind: crate::scene::folded::KIND,
        scene,
        report,
        run_id: None,
        files: std::collections::BTreeMap::new(),
    };
    Ok(serde_json::to_string(&written)?)
}

/// Takes `dir` for a run of the chain `scene` ([`RunFolder::take`], under the chain's run
/// id).
pub fn take_folder(scene: &FoldedChain, dir: &std::path::Path) -> Result<RunFolder, FolderError> {
    RunFolder::take(dir, &run_id(&scene.name, &scene.source_text), &scene.name)
}

/// Runs `scene` into `folder` (taken for it, so emptied of earlier runs' files):
/// `samples.csv` and `report.json`; each sample is also handed to `each`.
pub fn write_chain_run(
    scene: &FoldedChain,
    folder: &RunFolder,
    each: &mut dyn FnMut(&ChainSample) -> anyhow::Result<()>,
    stop: &AtomicBool,
) -> anyhow::Result<ChainReport> {
    let dir = folder.dir();
    let (csv_path, json_path) = (dir.join(SAMPLES), dir.join(REPORT));
    let tmp = partial_path(&csv_path);
    let file = File::create(&tmp).with_context(|| format!("cannot create {}", tmp.display()))?;
    let mut csv = csv::Writer::from_writer(file);
    let report = run_chain(
        scene,
        &mut |s| {
            csv.serialize(s)
                .with_context(|| format!("cannot write {}", tmp.display()))?;
            each(s)
        },
        stop,
    )?;
    let file = csv
        .into_inner()
        .map_err(|e| e.into_error())
        .and_then(|f| f.sync_all().map(|()| f))
        .with_context(|| format!("cannot write {}", tmp.display()))?;
    drop(file);
    fs::rename(&tmp, &csv_path)
        .with_context(|| format!("cannot rename to {}", csv_path.display()))?;
    let written = Written {
        kind: crate::scene::folded::KIND,
        scene,
        report: &report,
        run_id: Some(folder.run_id()),
        files: [(SAMPLES, FileStamp::of(&csv_path)?)].into(),
    };
    let mut text = serde_json::to_string_pretty(&written)?;
    text.push('\n');
    write_atomic(&json_path, text.as_bytes())?;
    Ok(report)
}

/// The summary's first two lines: the chain, its start and floor; the solver and how it did.
fn heading(scene: &FoldedChain, r: &ChainReport) -> String {
    let c = &scene.chain;
    let s = &scene.solver;
    let floor = match scene.start {
        Start::Hanging { .. } => format!("onto a floor (friction {})", scene.floor.friction),
        Start::Fold if scene.floor.enabled => format!(
            "onto a floor {} m below the pin (friction {})",
            scene.pin_height_m, scene.floor.friction
        ),
        Start::Fold => "no floor".to_owned(),
    };
    let solver = match s.joints {
        ChainJoints::Exact => format!(
            "the exact chain, a {} s step: {:.2} iterations a step on average, at most {}, {} \
             step(s) missed the tolerance; widest joint gap {:.1e} m, deepest contact {:.1e} m",
            s.dt_s,
            r.solve.mean_iterations(),
            r.solve.max_iterations,
            r.solve.missed_steps,
            r.solve.max_joint_gap_m,
            r.solve.max_penetration_m,
        ),
        joints => format!(
            "{} joints, {} substeps of a {} s step, {} relax sweep(s), joints at {:e} Hz",
            if joints == ChainJoints::Multibody {
                "multibody"
            } else {
                "impulse"
            },
            s.substeps,
            s.dt_s,
            s.relax_iterations,
            s.joint_hz,
        ),
    };
    let thick = if c.thickness_m > 0.0 {
        format!(", {} m thick", c.thickness_m)
    } else {
        String::new()
    };
    let shape = match scene.start {
        Start::Fold => format!("a folded chain of {} links{thick}", c.links),
        Start::Hanging { tilt_rad } => format!(
            "a hanging chain (Cayley's) of {} links{thick}, tilted {tilt_rad} rad either way",
            c.links
        ),
    };
    let ends = match scene.start {
        Start::Fold => format!(", ends {} m apart", c.separation_m),
        Start::Hanging { .. } => String::new(),
    };
    format!(
        "{}: {shape}, L = {} m, M = {} kg{ends}, {floor}\n\
         solver: {solver}\n",
        r.name, c.length_m, c.mass_kg,
    )
}

/// The readable summary of a folded chain's run.
pub fn chain_summary(scene: &FoldedChain, r: &ChainReport) -> String {
    let c = &scene.chain;
    let mut o = heading(scene, r);
    let end = match r.end {
        ChainEnd::TipFraction => format!("the tip fell {} L", scene.stop.tip_fraction),
        ChainEnd::Rest => "at rest".to_owned(),
        ChainEnd::MaxTime => "max time".to_owned(),
        ChainEnd::Interrupted => "interrupted".to_owned(),
        ChainEnd::NotFinite => "stopped: the state is no longer finite".to_owned(),
        ChainEnd::Unsolved => "stopped: the exact chain's solve failed".to_owned(),
    };
    o.push_str(&format!(
        "ended: {end} at t = {:.4} s ({} steps, engine {:.2} s)\n\n",
        r.t_end_s, r.steps, r.wall_time_s
    ));
    let g = scene.gravity.g_m_s2;
    match &r.cayley {
        None => {
            o.push_str("The tip against the closed form (separation 0, energy conserved):\n");
            o.push_str(&crossing_table(&r.crossings).text("  "));
            if r.crossings.iter().any(|c| !c.closed_form_applies) {
                o.push_str(
                    "  * the fold or the tip had reached the floor: the closed form no longer \
                     applies\n",
                );
            }
            o.push_str(&format!(
                "  closed-form fall time t(L) = {:.5} s = {:.4} sqrt(2L/g)\n\n",
                r.fall_time_closed_s,
                r.fall_time_closed_s / (2.0 * c.length_m / g).sqrt()
            ));
        }
        Some(cayley) => o.push_str(&cayley_text(r, cayley)),
    }
    let l = &r.ledger;
    let lost = r.released_j - r.kinetic_j;
    let share = |v: f64| {
        if r.released_j > 0.0 {
            format!("{:.3} %", 100.0 * v / r.released_j)
        } else {
            "-".into()
        }
    };
    o.push_str(&format!(
        "Energy at the end, as shares of the {:.6e} J released: kinetic {}, lost {}\n  \
         floor impacts {}, floor friction {}{}, joints {}, residual {}; numerical (|joints| + \
         |residual|) {}\n",
        r.released_j,
        share(r.kinetic_j),
        share(lost),
        share(l.floor_normal_j),
        share(l.floor_friction_j),
        if c.thickness_m > 0.0 {
            format!(
                ", the links' impacts on each other {}, their friction {}",
                share(l.layers_normal_j),
                share(l.layers_friction_j)
            )
        } else {
            String::new()
        },
        share(l.joints_j),
        share(l.residual_j),
        share(l.numerical_j()),
    ));
    o
}

/// Cayley's comparisons: the top against free fall, the table's force against
/// `3 lambda g x`.
fn cayley_text(r: &ChainReport, c: &CayleyReport) -> String {
    let mut o = String::from("The top against free fall (x = g t^2 / 2):\n");
    o.push_str(&crossing_table(&r.crossings).text("  "));
    if r.crossings.iter().any(|c| !c.closed_form_applies) {
        o.push_str("  * the top had reached the pile: free fall no longer applies\n");
    }
    let [lag, lead] = c.free_fall_deviation;
    o.push_str(&format!(
        "  in flight (x = 0.1 L to {:.3} L), v / sqrt(2 g x) - 1 within {lag:+.1e} .. {lead:+.1e}\n\n",
        c.flight_fraction
    ));
    o.push_str("The table's force against 3 lambda g x (Cayley), impulse over each window:\n");
    let mut t = Table::new(["x/L", "force / 3 lambda g x"]);
    for w in &c.table {
        let note = if w.in_flight { "" } else { " *" };
        t.push([
            format!("{}-{}{note}", w.from_fraction, w.to_fraction),
            format!("{:.3}", w.ratio),
        ]);
    }
    o.push_str(&t.text("  "));
    if c.table.iter().any(|w| !w.in_flight) {
        o.push_str("  * the top had reached the pile, which Cayley's has no height\n");
    }
    o.push_str(&format!(
        "  in flight (x = 0.1 L to {:.3} L): {:.3}\n\n",
        c.flight_fraction, c.flight_ratio
    ));
    o
}

/// The crossings as a table: time and speed against the closed form, and the joints' work.
fn crossing_table(crossings: &[Crossing]) -> Table {
    let mut t = Table::new([
        "x/L",
        "t (s)",
        "closed",
        "t error",
        "v (m/s)",
        "closed",
        "v error",
        "joints / released",
        "numerical / released",
    ]);
    let pct = |a: f64, b: f64| format!("{:+.3} %", 100.0 * (a / b - 1.0));
    for c in crossings {
        let note = if c.closed_form_applies { "" } else { " *" };
        t.push([
            format!("{}{note}", c.fraction),
            format!("{:.5}", c.t_s),
            format!("{:.5}", c.t_closed_s),
            pct(c.t_s, c.t_closed_s),
            format!("{:.4}", c.speed_m_s),
            format!("{:.4}", c.speed_closed_m_s),
            pct(c.speed_m_s, c.speed_closed_m_s),
            format!("{:.3} %", 100.0 * c.joints_j / c.released_j),
            format!("{:.3} %", 100.0 * c.numerical_j / c.released_j),
        ]);
    }
    t
}
