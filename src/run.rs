//! The run layer: steps the contact-resolved model, puts the analytic references beside
//! it, and feeds samples, frames and events to observers; it builds the [`RunReport`]. It
//! times only the model's step, and it never names a file format (outputs are
//! [`Observer`]s).

pub mod folded;
pub mod force_window;
pub mod frame;
pub mod guard;
pub mod limits;
pub mod milestones;
pub mod report;
mod runner;
pub mod sample;
pub mod signals;
pub mod stop;

use std::sync::Arc;
use std::sync::atomic::AtomicBool;

pub use milestones::{SPOOL_FRACTIONS, milestone_radii};
pub use report::{
    Approach, BANG_SPLIT_MIN_OF_SCALE, BangReport, Ledger, Milestone, RivalTimes, RunReport,
};
pub use runner::{BANG_DRAWN_STEPS, BANG_FRAMES_PER_DECADE, bang_frame_growth};
pub use sample::{Sample, SampleInputs};

use crate::run::frame::{Event, Frame};
use crate::scene::Scene;
use crate::theory::References;

/// An output fed by the run loop.
pub trait Observer {
    /// Called once before the first step.
    fn observe_init(&mut self, scene: &Scene) -> anyhow::Result<()>;
    /// Called for every sample.
    fn observe_sample(&mut self, sample: &Sample) -> anyhow::Result<()>;
    /// Called once with the final report.
    fn observe_final(&mut self, report: &RunReport) -> anyhow::Result<()>;
    /// Whether this observer draws frames; frames are built only if one does (default:
    /// no).
    fn wants_frames(&self) -> bool {
        false
    }
    /// Called `output.scene_rate_hz` times per simulated second with the geometry, at the
    /// first and last step, and in the final bang at its own pace ([`BANG_DRAWN_STEPS`]), if
    /// [`Observer::wants_frames`] (default: ignored).
    fn observe_frame(&mut self, _frame: &Frame) -> anyhow::Result<()> {
        Ok(())
    }
    /// Called for every event, in time order (default: ignored).
    fn observe_event(&mut self, _event: &Event) -> anyhow::Result<()> {
        Ok(())
    }
    /// Whether this observer makes its samples itself, from [`Observer::observe_step`] and
    /// the references of [`Observer::observe_references`], instead of being handed them by
    /// [`Observer::observe_sample`] (default: no). An observer on a thread of its own makes
    /// them there, off the run's thread.
    fn makes_samples(&self) -> bool {
        false
    }
    /// Called once, after [`Observer::observe_init`], with the run's references, if
    /// [`Observer::makes_samples`].
    fn observe_references(&mut self, _refs: &Arc<References>) -> anyhow::Result<()> {
        Ok(())
    }
    /// Called for every sample with what it is made from, if [`Observer::makes_samples`].
    fn observe_step(&mut self, _step: &SampleInputs) -> anyhow::Result<()> {
        Ok(())
    }
}

/// Runs a scene to its end and returns the report; every sample goes to the observers.
pub fn run(scene: &Scene, observers: &mut [&mut dyn Observer]) -> anyhow::Result<RunReport> {
    run_until(scene, observers, &AtomicBool::new(false))
}

/// Like [`run`], but stops early, with every observer finalised, once `stop` is set (e.g.
/// by a Ctrl-C handler); the flag is polled after every step.
pub fn run_until(
    scene: &Scene,
    observers: &mut [&mut dyn Observer],
    stop: &AtomicBool,
) -> anyhow::Result<RunReport> {
    run_until_with(scene, Arc::new(References::new(scene)), observers, stop)
}

/// [`run_until`] with the scene's references already built (`References::new(scene)`, by
/// a sweep while its previous run stepped).
pub fn run_until_with(
    scene: &Scene,
    refs: Arc<References>,
    observers: &mut [&mut dyn Observer],
    stop: &AtomicBool,
) -> anyhow::Result<RunReport> {
    let mut runner = runner::Runner::new(scene, refs, observers)?;
    loop {
        if let Some(end) = runner.step(observers, stop)? {
            return runner.finish(end, observers);
        }
    }
}
