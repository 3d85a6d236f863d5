//! The folded chain's run: the engine's chain stepped beside the closed form of its fall
//! ([`FoldedFall`]), the tip's crossings of the fractions of `L` timed, and the energy
//! released, the joints' work and the floor's booked there. It times only the engine's
//! step and writes no file (its samples go to a callback).

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use serde::{Deserialize, Serialize};

use crate::model::BangLedger;
use crate::model::exact_chain::SolveStats;
use crate::model::folded::{ChainState, FoldedModel};
use crate::scene::folded::FoldedChain;
use crate::theory::folded::FoldedFall;

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
    /// Kinetic energy (J).
    pub kinetic_j: f64,
    /// Potential energy released since the start (J).
    pub released_j: f64,
    /// Dissipated since the start, by mechanism (J).
    pub floor_normal_j: f64,
    /// ... by the floor's friction (J).
    pub floor_friction_j: f64,
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
}

/// Runs `scene`, handing each sample due to `on_sample`, until its stop rule, `max_time_s`
/// or `stop`.
pub fn run_chain(
    scene: &FoldedChain,
    on_sample: &mut dyn FnMut(&ChainSample) -> anyhow::Result<()>,
    stop: &AtomicBool,
) -> anyhow::Result<ChainReport> {
    let c = &scene.chain;
    let fall = FoldedFall::new(c.length_m, c.mass_kg, scene.gravity.g_m_s2);
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
    })
}

/// A sample of `s` beside the closed form at its `x`; the pin's force is its mean since
/// the sample `last`.
fn sample(fall: &FoldedFall, last: &ChainState, s: &ChainState) -> ChainSample {
    let x = s.x_m.max(0.0);
    let span = s.t - last.t;
    ChainSample {
        t_s: s.t,
        x_m: s.x_m,
        speed_m_s: s.speed_m_s,
        speed_closed_m_s: fall.speed(x),
        pin_force_n: (span > 0.0).then(|| (s.pin_impulse_ns - last.pin_impulse_ns) / span),
        pin_force_closed_n: fall.pin_force(x),
        kinetic_j: s.kinetic_j,
        released_j: s.released_j,
        floor_normal_j: s.ledger.floor_normal_j,
        floor_friction_j: s.ledger.floor_friction_j,
        joints_j: s.ledger.joints_j,
        residual_j: s.ledger.residual_j,
    }
}

/// The crossing of `fraction` of `L` between the states `a` and `b`, linear in `x`.
fn crossing(
    scene: &FoldedChain,
    fall: &FoldedFall,
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
        closed_form_applies: !scene.floor.enabled || (0.5 * (length + x) < h && x < h),
    }
}
