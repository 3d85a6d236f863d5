//! Helpers shared by the test modules.

use uncoil::output::compare::SampleLog;
use uncoil::run::{RunReport, Sample, run};
use uncoil::scene::Scene;

/// Runs `scene` keeping every sample in memory; returns them with the report.
pub fn run_kept(scene: &Scene) -> (Vec<Sample>, RunReport) {
    let mut log = SampleLog::default();
    let report = run(scene, &mut [&mut log]).unwrap();
    (log.samples, report)
}
