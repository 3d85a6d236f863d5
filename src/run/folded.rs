//! The folded chain's run: the engine's chain stepped beside the closed form of its fall
//! ([`FoldedFall`], or Cayley's [`CayleyFall`] for a hanging start), the tip's crossings of
//! the fractions of `L` timed, and the energy released, the joints' work and the floor's
//! booked there; for Cayley's chain, the table's force against `3 lambda g x` over windows
//! of the fall and the top's fall against free fall. It times only the engine's step and
//! writes no file (its samples go to a callback).

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use serde::{Deserialize, Serialize};

use crate::model::BangLedger;
use crate::model::exact_chain::SolveStats;
use crate::model::folded::{ChainState, FoldedModel};
use crate::scene::folded::{FoldedChain, Start};
use crate::theory::folded::{CayleyFall, ChainFall, FoldedFall};

/// The fractions of `L` at which the tip's fall is timed.
pub const FRACTIONS: [f64; 5] = [0.25, 0.5, 0.75, 0.9, 0.95];

/// One row of the chain's `samples.csv`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct ChainSample {
    /// Simulated time (s).
    pub t_s: f64,
    /// How far the free end has fallen (m).
    pub x_m: f64,
    /// The tip's downward speed (m/s).
    pub speed_m_s: f64,
    /// The closed form's speed at the same `x` (m/s).
    pub speed_closed_m_s: f64,
    /// The pin's upward force, its mean since the last sample (N; none in the first row).
    /// The discrete chain's links reach the fold one at a time, each a small impact at the
    /// pin, so it scatters about the closed form's over a link's arrival time.
    pub pin_force_n: Option<f64>,
    /// The closed form's pin force at the same `x` (N).
    pub pin_force_closed_n: f64,
    /// The floor's upward force, its mean since the last sample (N; none in the first row,
    /// 0 without a floor).
    pub floor_force_n: Option<f64>,
    /// The closed form's floor force at the same `x`, where it has one: Cayley's
    /// `3 lambda g x` (N).
    pub floor_force_closed_n: Option<f64>,
    /// Kinetic energy (J).
    pub kinetic_j: f64,
    /// Potential energy released since the start (J).
    pub released_j: f64,
    /// Dissipated since the start, by mechanism (J).
    pub floor_normal_j: f64,
    /// ... by the floor's friction (J).
    pub floor_friction_j: f64,
    /// ... by the links' impacts on each other (J; with a thickness).
    pub layers_normal_j: f64,
    /// ... by their friction on each other (J).
    pub layers_friction_j: f64,
    /// ... by the joints (J; positive = dissipated).
    pub joints_j: f64,
    /// What the split leaves of the energy lost (J).
    pub residual_j: f64,
}

/// The tip's crossing of `fraction` of `L`, interpolated between the steps around it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Crossing {
    /// The fraction of `L`.
    pub fraction: f64,
    /// Simulated time (s).
    pub t_s: f64,
    /// The closed form's time there (s).
    pub t_closed_s: f64,
    /// The tip's downward speed (m/s).
    pub speed_m_s: f64,
    /// The closed form's speed at the same `x` (m/s).
    pub speed_closed_m_s: f64,
    /// Potential energy released by then (J).
    pub released_j: f64,
    /// Work the joints had taken by then (J; positive = dissipated).
    pub joints_j: f64,
    /// `|joints| + |residual|` by then (J).
    pub numerical_j: f64,
    /// Whether the closed form applies there: no floor, or the fold and the tip still above
    /// it.
    pub closed_form_applies: bool,
}

/// The fractions of `L` that bound the windows over which Cayley's table force is
/// compared: from a tenth (the first links' landings are single impacts) to nine tenths
/// (a pile of some height is reached before `L`; each window says whether the top was
/// still in flight through it).
pub const TABLE_WINDOWS: [f64; 5] = [0.1, 0.3, 0.5, 0.7, 0.9];

/// Cayley's table force over one window of the fall.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TableWindow {
    /// Where the window starts, as the fraction of `L` the top has fallen.
    pub from_fraction: f64,
    /// Where it ends, likewise.
    pub to_fraction: f64,
    /// The floor's impulse over the window over the closed form's, `int 3 lambda g x dt`,
    /// at the run's own `x(t)`.
    pub ratio: f64,
    /// Whether the top was still in flight through the whole window (the closed form's
    /// pile has no height; past the flight the top has landed on a pile that has).
    pub in_flight: bool,
}

/// What a hanging chain's run found against Cayley's closed form.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CayleyReport {
    /// The table's force against `3 lambda g x` in each of [`TABLE_WINDOWS`]' windows the
    /// top crossed.
    pub table: Vec<TableWindow>,
    /// The top's fall against free fall while in flight: the least and the greatest of
    /// `v / sqrt(2 g x) - 1` from `x = 0.1 L` (past the start, where the chain buckles off
    /// its lowest link) until the top reaches the pile (its speed first falls below 0.99 of
    /// free fall's at its `x`). Its speed at its fall, so a delay at the start does not count.
    pub free_fall_deviation: [f64; 2],
    /// How far the top had fallen when it reached the pile, as a fraction of `L`.
    pub flight_fraction: f64,
    /// The table's impulse over the closed form's from `x = 0.1 L` to the end of the flight:
    /// the windows' comparison in one figure.
    pub flight_ratio: f64,
}

/// Why the chain's run ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ChainEnd {
    /// The tip fell `stop.tip_fraction` of `L` (no floor).
    TipFraction,
    /// On the floor, the kinetic energy fell below `stop.rest_fraction` of what was released.
    Rest,
    /// `stop.max_time_s` passed first.
    MaxTime,
    /// Stopped from outside (Ctrl-C).
    Interrupted,
    /// A position or velocity stopped being finite.
    NotFinite,
    /// The exact chain's solve failed (a singular system or a non-finite impulse); the
    /// step that failed was not taken.
    Unsolved,
}

/// What a folded chain's run found.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ChainReport {
    /// The scene's name.
    pub name: String,
    /// Links in the chain.
    pub links: u32,
    /// Why the run ended.
    pub end: ChainEnd,
    /// Simulated time at the end (s).
    pub t_end_s: f64,
    /// Engine steps taken.
    pub steps: u64,
    /// Wall time of the engine's steps (s).
    pub wall_time_s: f64,
    /// The closed form's time to fall the whole length (s).
    pub fall_time_closed_s: f64,
    /// The tip's crossings of [`FRACTIONS`] of `L`, as far as it fell.
    pub crossings: Vec<Crossing>,
    /// At the end: energy released, kinetic energy, and the ledger (J).
    pub released_j: f64,
    /// Kinetic energy (J).
    pub kinetic_j: f64,
    /// Dissipated by mechanism at the end (J).
    pub ledger: BangLedger,
    /// How the exact chain's steps were solved (all zero on the engine's joints).
    #[serde(default)]
    pub solve: SolveStats,
    /// Against Cayley's closed form, for a hanging start.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cayley: Option<CayleyReport>,
}

/// Cayley's comparisons, gathered step by step.
struct CayleyTally {
    /// The floor's impulse and the closed form's, in each window (N s).
    windows: Vec<(f64, f64)>,
    deviation: [f64; 2],
    /// Where the top reached the pile, once it has.
    landed: Option<f64>,
    /// The floor's impulse and the closed form's in flight from 0.1 L (N s).
    flight: (f64, f64),
}

impl CayleyTally {
    fn new() -> Self {
        Self {
            windows: vec![(0.0, 0.0); TABLE_WINDOWS.len() - 1],
            deviation: [0.0; 2],
            landed: None,
            flight: (0.0, 0.0),
        }
    }

    /// Books the step from `a` to `b`.
    fn add(&mut self, fall: &CayleyFall, length: f64, a: &ChainState, b: &ChainState) {
        let x = 0.5 * (a.x_m + b.x_m);
        let (got, closed) = (
            b.floor_impulse_ns - a.floor_impulse_ns,
            fall.table_force(x) * (b.t - a.t),
        );
        if let Some(w) = TABLE_WINDOWS
            .windows(2)
            .position(|w| (w[0] * length..w[1] * length).contains(&x))
        {
            self.windows[w].0 += got;
            self.windows[w].1 += closed;
        }
        if self.landed.is_none() && x >= TABLE_WINDOWS[0] * length {
            self.flight.0 += got;
            self.flight.1 += closed;
        }
        if self.landed.is_none() && b.x_m >= TABLE_WINDOWS[0] * length {
            let d = b.speed_m_s / fall.speed(b.x_m) - 1.0;
            if d < -0.01 {
                self.landed = Some(b.x_m / length);
            } else {
                self.deviation = [self.deviation[0].min(d), self.deviation[1].max(d)];
            }
        }
    }

    fn report(&self, reached: f64) -> CayleyReport {
        let flight_fraction = self.landed.unwrap_or(reached);
        CayleyReport {
            table: TABLE_WINDOWS
                .windows(2)
                .zip(&self.windows)
                .filter(|(w, _)| reached >= w[1])
                .map(|(w, &(got, closed))| TableWindow {
                    from_fraction: w[0],
                    to_fraction: w[1],
                    ratio: got / closed,
                    in_flight: w[1] <= flight_fraction,
                })
                .collect(),
            free_fall_deviation: self.deviation,
            flight_fraction,
            flight_ratio: self.flight.0 / self.flight.1,
        }
    }
}

/// Runs `scene`, handing each sample due to `on_sample`, until its stop rule, `max_time_s`
/// or `stop`.
pub fn run_chain(
    scene: &FoldedChain,
    on_sample: &mut dyn FnMut(&ChainSample) -> anyhow::Result<()>,
    stop: &AtomicBool,
) -> anyhow::Result<ChainReport> {
    let c = &scene.chain;
    let g = scene.gravity.g_m_s2;
    let fall = match scene.start {
        Start::Fold => ChainFall::Folded(FoldedFall::new(c.length_m, c.mass_kg, g)),
        Start::Hanging { .. } => ChainFall::Cayley(CayleyFall::new(c.length_m, c.mass_kg, g)),
    };
    let mut cayley = matches!(fall, ChainFall::Cayley(_)).then(CayleyTally::new);
    let mut reached = 0.0_f64;
    let mut model = FoldedModel::new(scene);
    let mut prev = model.state();
    on_sample(&sample(&fall, &prev, &prev))?;
    let mut last_sample = prev;
    let mut next_sample = scene.sample_interval_s;
    let mut crossings = Vec::new();
    let (mut steps, mut wall) = (0u64, 0.0);
    let end = loop {
        if stop.load(Ordering::Relaxed) {
            break ChainEnd::Interrupted;
        }
        let clock = Instant::now();
        let stepped = model.step();
        wall += clock.elapsed().as_secs_f64();
        let Ok(s) = stepped else {
            break ChainEnd::Unsolved;
        };
        steps += 1;
        if let (Some(tally), ChainFall::Cayley(f)) = (&mut cayley, &fall) {
            tally.add(f, c.length_m, &prev, &s);
        }
        reached = reached.max(s.x_m / c.length_m);
        if ![s.x_m, s.speed_m_s, s.kinetic_j, s.released_j]
            .iter()
            .all(|v| v.is_finite())
        {
            break ChainEnd::NotFinite;
        }
        for &f in FRACTIONS.iter().skip(crossings.len()) {
            let x = f * c.length_m;
            if s.x_m < x {
                break;
            }
            crossings.push(crossing(scene, &fall, f, &prev, &s));
        }
        if s.t + 1e-12 >= next_sample {
            on_sample(&sample(&fall, &last_sample, &s))?;
            last_sample = s;
            next_sample += scene.sample_interval_s;
        }
        prev = s;
        if !scene.floor.enabled && s.x_m >= scene.stop.tip_fraction * c.length_m {
            break ChainEnd::TipFraction;
        }
        if scene.floor.enabled && s.kinetic_j < scene.stop.rest_fraction * s.released_j {
            break ChainEnd::Rest;
        }
        if s.t >= scene.stop.max_time_s {
            break ChainEnd::MaxTime;
        }
    };
    Ok(ChainReport {
        name: scene.name.clone(),
        links: c.links,
        end,
        t_end_s: prev.t,
        steps,
        wall_time_s: wall,
        fall_time_closed_s: fall.fall_time(),
        crossings,
        released_j: prev.released_j,
        kinetic_j: prev.kinetic_j,
        ledger: prev.ledger,
        solve: model.solve_stats(),
        cayley: cayley.map(|t| t.report(reached)),
    })
}

/// A sample of `s` beside the closed form at its `x`; the pin's force is its mean since
/// the sample `last`.
fn sample(fall: &ChainFall, last: &ChainState, s: &ChainState) -> ChainSample {
    let x = s.x_m.max(0.0);
    let span = s.t - last.t;
    ChainSample {
        t_s: s.t,
        x_m: s.x_m,
        speed_m_s: s.speed_m_s,
        speed_closed_m_s: fall.speed(x),
        pin_force_n: (span > 0.0).then(|| (s.pin_impulse_ns - last.pin_impulse_ns) / span),
        pin_force_closed_n: fall.pin_force(x),
        floor_force_n: (span > 0.0).then(|| (s.floor_impulse_ns - last.floor_impulse_ns) / span),
        floor_force_closed_n: fall.floor_force(x),
        kinetic_j: s.kinetic_j,
        released_j: s.released_j,
        floor_normal_j: s.ledger.floor_normal_j,
        floor_friction_j: s.ledger.floor_friction_j,
        layers_normal_j: s.ledger.layers_normal_j,
        layers_friction_j: s.ledger.layers_friction_j,
        joints_j: s.ledger.joints_j,
        residual_j: s.ledger.residual_j,
    }
}

/// The crossing of `fraction` of `L` between the states `a` and `b`, linear in `x`.
fn crossing(
    scene: &FoldedChain,
    fall: &ChainFall,
    fraction: f64,
    a: &ChainState,
    b: &ChainState,
) -> Crossing {
    let length = scene.chain.length_m;
    let x = fraction * length;
    let w = if b.x_m > a.x_m {
        ((x - a.x_m) / (b.x_m - a.x_m)).clamp(0.0, 1.0)
    } else {
        1.0
    };
    let at = |p: f64, q: f64| p + w * (q - p);
    let numerical = |s: &ChainState| s.ledger.joints_j.abs() + s.ledger.residual_j.abs();
    let h = scene.pin_height_m;
    let t_closed_s = fall.time_at(x).unwrap_or(f64::NAN);
    Crossing {
        fraction,
        t_s: at(a.t, b.t),
        t_closed_s,
        speed_m_s: at(a.speed_m_s, b.speed_m_s),
        speed_closed_m_s: fall.speed(x),
        released_j: at(a.released_j, b.released_j),
        joints_j: at(a.ledger.joints_j, b.ledger.joints_j),
        numerical_j: at(numerical(a), numerical(b)),
        closed_form_applies: match scene.start {
            Start::Fold => !scene.floor.enabled || (0.5 * (length + x) < h && x < h),
            // Until the top reaches the pile.
            Start::Hanging { .. } => b.speed_m_s >= 0.99 * fall.speed(b.x_m),
        },
    }
}
