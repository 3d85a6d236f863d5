//! The size of the run a valid scene asks for, held to stated budgets: engine steps, links,
//! samples and drawn link nodes, each estimated from the scene's own keys, so that no value
//! makes a run endless or absurdly long (`solver.max_dt_s = 1e-308` would be 6e310 steps).
//! The estimates are what a run takes at least when it goes on to `stop.max_time_s`; it does
//! not simulate anything, and it checks values the other rules have already accepted.
//!
//! The budgets are generous: every shipped scene, and every value the tests and the sweeps
//! of `tools/sweeps.sh` set, stays at least ten times below each (see the tests).

use crate::scene::rules::{Shown, invalid};
use crate::scene::{Scene, SceneError, Tape};

/// Engine steps a run may take (count). A step of a small scene takes about 0.1 ms (the
/// yoga mat: 3091 steps in 0.43 s), so 1e8 steps are hours. A run takes at least
/// `stop.max_time_s / solver.max_dt_s` steps if it goes on to its time limit, and at least
/// `solver.steps_per_link` per link while the coil rolls (the coil turns once per turn shed).
/// Largest used: 6e6 (60 s at `max_dt_s = 1e-5`, the test of an interrupted run) and 6.1e5
/// steps per link (the thin tape at 256 links per turn and 8 steps each in
/// `tools/sweeps.sh`); of a shipped scene, 3e5 (`scenes/hard/thin-1000.toml`: 300 s at
/// 1 ms) and 9.6e4.
pub const MAX_ENGINE_STEPS: f64 = 1.0e8;

/// The rotation of the fastest piece in the final bang that [`MIN_BANG_STEP_RAD`] is sized
/// for (rad): the thin tape's bang turns it through about 8e3 rad (26 465 steps at
/// `solver.bang_step_rad = 0.3`, each turning it by at most that).
pub const BANG_TURN_RAD: f64 = 1.0e4;

/// Smallest `solver.bang_step_rad` (rad): the bang's step turns its fastest piece by at most
/// this, so a bang turning it through [`BANG_TURN_RAD`] takes [`MAX_ENGINE_STEPS`] steps at
/// it. Smallest used: 0.02 (the spools, the single turn).
pub const MIN_BANG_STEP_RAD: f64 = BANG_TURN_RAD / MAX_ENGINE_STEPS;

/// Links a tape may have (count, turns times `discretisation.links_per_turn`): the model
/// keeps every link's geometry in memory and every drawing holds every link. Largest used:
/// 1e5 (the thin tape at 333 links per turn in `tools/sweeps.sh`); of a shipped scene,
/// 2.4e4 (`scenes/hard/thin-1000.toml`).
pub const MAX_LINKS: f64 = 1.0e6;

/// Rows of `samples.csv` a run may write (count): a row is about 800 bytes, so 1e7 rows are
/// 8 GB. A run writes at least `stop.max_time_s / max(output.sample_interval_s,
/// solver.max_dt_s)` if it goes on to its time limit (at most one row per step). Largest
/// used: 3e5 (`scenes/hard/thin-1000.toml`); the longest run allowed, 1e4 s, at the default
/// 1 ms, is exactly 1e7.
pub const MAX_SAMPLES: f64 = 1.0e7;

/// Link nodes the drawings of a run may hold (count, drawings times links + 1): each of
/// the `output.scene_rate_hz` drawings per simulated second (at most one per step) holds
/// every link's node, two `f64` (16 bytes) before compression, so 1e11 are 1.6 TB.
/// Largest used: 7.2e8 (`scenes/hard/thin-1000.toml`, 300 s at 100 Hz of 2.4e4 links);
/// the budget lets the largest tape ([`MAX_LINKS`]) be drawn at the default 100 Hz for
/// about 1000 s. The final bang's own drawings (its first 200 steps, then 100 a decade of
/// its time since the release: a few thousand at most) are not counted.
pub const MAX_FRAME_NODES: f64 = 1.0e11;

/// Whole turns of the tape's midline between the core and the outer turn, `(R - core - b) /
/// b` (count, not rounded).
pub(super) fn turns(tape: &Tape) -> f64 {
    (tape.outer_radius_m - tape.core_radius_m - tape.thickness_m) / tape.thickness_m
}

/// Links of the tape at `links_per_turn` (count, not rounded).
pub(super) fn links(tape: &Tape, links_per_turn: u32) -> f64 {
    turns(tape) * f64::from(links_per_turn)
}

/// A count as written in messages: `6.000e9`, or `more than 1e308` past the largest `f64`.
fn count(n: f64) -> String {
    if n.is_finite() {
        format!("{n:.3e}")
    } else {
        "more than 1e308".to_owned()
    }
}

/// Holds the run `s` asks for to the budgets, in the order of its keys in the file; the
/// first one exceeded is reported on the key that sets it.
pub(super) fn check(s: &Scene) -> Result<(), SceneError> {
    let t_max = s.stop.max_time_s;
    let dt = s.solver.max_dt_s;
    let steps = t_max / dt;
    if steps > MAX_ENGINE_STEPS {
        return Err(invalid(
            "solver.max_dt_s",
            Shown(dt),
            format!(
                "must be >= stop.max_time_s / {MAX_ENGINE_STEPS:e} (= {}): a run may take at \
                 most {MAX_ENGINE_STEPS:e} engine steps, and stop.max_time_s = {t_max} s at \
                 this step is {}",
                Shown(t_max / MAX_ENGINE_STEPS),
                count(steps)
            ),
        ));
    }
    let links = links(&s.tape, s.discretisation.links_per_turn);
    let per_link = s.solver.steps_per_link;
    if links * per_link > MAX_ENGINE_STEPS {
        return Err(invalid(
            "solver.steps_per_link",
            Shown(per_link),
            format!(
                "must be <= {MAX_ENGINE_STEPS:e} / the tape's {links:.0} links (= {:.1}): a run \
                 may take at most {MAX_ENGINE_STEPS:e} engine steps, and rolling through its \
                 links at this many steps each is {}",
                MAX_ENGINE_STEPS / links,
                count(links * per_link)
            ),
        ));
    }
    let bang_step = s.solver.bang_step_rad;
    if bang_step < MIN_BANG_STEP_RAD {
        return Err(invalid(
            "solver.bang_step_rad",
            Shown(bang_step),
            format!(
                "must be >= {MIN_BANG_STEP_RAD}: a run may take at most {MAX_ENGINE_STEPS:e} \
                 engine steps, and a final bang that turns its fastest piece through \
                 {BANG_TURN_RAD:e} rad (the thin tape's: 8e3) at this step is {}",
                count(BANG_TURN_RAD / bang_step)
            ),
        ));
    }
    let every = s.output.sample_interval_s.max(dt);
    if t_max / every > MAX_SAMPLES {
        return Err(invalid(
            "output.sample_interval_s",
            Shown(s.output.sample_interval_s),
            format!(
                "must be >= stop.max_time_s / {MAX_SAMPLES:e} (= {}): a run may write at most \
                 {MAX_SAMPLES:e} samples, and stop.max_time_s = {t_max} s sampled every \
                 max(output.sample_interval_s, solver.max_dt_s) = {} s is {}",
                Shown(t_max / MAX_SAMPLES),
                Shown(every),
                count(t_max / every)
            ),
        ));
    }
    let rate = s.output.scene_rate_hz;
    let drawn = t_max * rate.min(1.0 / dt) * (links + 1.0);
    if drawn > MAX_FRAME_NODES {
        return Err(invalid(
            "output.scene_rate_hz",
            Shown(rate),
            format!(
                "must be <= {MAX_FRAME_NODES:e} / (stop.max_time_s * the tape's {:.0} nodes) \
                 (= {:.4}), or 0 for no drawings: a run's drawings may hold at most \
                 {MAX_FRAME_NODES:e} link nodes, and stop.max_time_s = {t_max} s of them at \
                 min(output.scene_rate_hz, 1 / solver.max_dt_s) = {} Hz is {}",
                links + 1.0,
                MAX_FRAME_NODES / (t_max * (links + 1.0)),
                Shown(rate.min(1.0 / dt)),
                count(drawn)
            ),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::overrides::{Override, scene_with_overrides};
    use crate::scene::tests::{err, rejects, with};

    const THIN_1000: &str = include_str!("../../scenes/hard/thin-1000.toml");
    const THIN: &str = include_str!("../../scenes/thin-tape.toml");
    const YOGA: &str = include_str!("../../scenes/yoga-mat.toml");

    /// `text` with the overrides `sets` (`KEY=VALUE`), which must load.
    fn loads(text: &str, sets: &[&str]) -> Scene {
        let o: Vec<Override> = sets.iter().map(|a| a.parse().unwrap()).collect();
        scene_with_overrides(text, "t", &o).unwrap_or_else(|e| panic!("{sets:?}: {e}"))
    }

    /// The error of `text` with the overrides `sets`, which must fail.
    fn fails(text: &str, sets: &[&str]) -> String {
        let o: Vec<Override> = sets.iter().map(|a| a.parse().unwrap()).collect();
        match scene_with_overrides(text, "t", &o) {
            Ok(_) => panic!("{sets:?} accepted"),
            Err(e) => e.to_string(),
        }
    }

    /// Each estimate of `s` over its budget, as a fraction of it.
    fn shares(s: &Scene) -> [f64; 5] {
        let t = s.stop.max_time_s;
        let dt = s.solver.max_dt_s;
        let n = links(&s.tape, s.discretisation.links_per_turn);
        [
            t / dt / MAX_ENGINE_STEPS,
            n * s.solver.steps_per_link / MAX_ENGINE_STEPS,
            n / MAX_LINKS,
            t / s.output.sample_interval_s.max(dt) / MAX_SAMPLES,
            t * s.output.scene_rate_hz.min(1.0 / dt) * (n + 1.0) / MAX_FRAME_NODES,
        ]
    }

    #[test]
    fn a_tiny_step_is_rejected_with_the_budget() {
        let msg = rejects("solver", "max_dt_s", "1e-308");
        assert_eq!(
            msg,
            "solver.max_dt_s = 1e-308: must be >= stop.max_time_s / 1e8 (= 6e-7): a run may \
             take at most 1e8 engine steps, and stop.max_time_s = 60 s at this step is more than 1e308"
        );
        // The bound is the budget exactly: 1e4 s at 1e-4 s is 1e8 steps.
        let text = with("solver", "max_dt_s", "1e-4") + "[stop]\nmax_time_s = 1e4\n";
        assert!(Scene::from_toml_str(&text, "t").is_ok());
        let text = with("solver", "max_dt_s", "0.99e-4") + "[stop]\nmax_time_s = 1e4\n";
        assert!(err(&text).starts_with("solver.max_dt_s = 0.000099: must be >= "));
    }

    #[test]
    fn too_many_steps_per_link_are_rejected() {
        // The thin tape of 1000 turns at 4096 links per turn: 4.1e6 links, rejected by the
        // link count first; at 1000 links per turn and 1000 steps per link, 1e9 steps.
        let msg = fails(
            THIN_1000,
            &[
                "discretisation.links_per_turn=4096",
                "solver.steps_per_link=1000",
            ],
        );
        assert!(
            msg.starts_with("discretisation.links_per_turn = 4096: the tape would have"),
            "{msg}"
        );
        let msg = fails(
            THIN_1000,
            &[
                "discretisation.links_per_turn=1000",
                "solver.steps_per_link=1000",
            ],
        );
        assert_eq!(
            msg,
            "solver.steps_per_link = 1000: must be <= 1e8 / the tape's 999000 links (= 100.1): \
             a run may take at most 1e8 engine steps, and rolling through its links at this \
             many steps each is 9.990e8"
        );
        loads(
            THIN_1000,
            &[
                "discretisation.links_per_turn=1000",
                "solver.steps_per_link=100",
            ],
        );
    }

    #[test]
    fn a_tiny_bang_step_is_rejected() {
        let msg = rejects("solver", "bang_step_rad", "1e-9");
        assert_eq!(
            msg,
            "solver.bang_step_rad = 1e-9: must be >= 0.0001: a run may take at most 1e8 engine \
             steps, and a final bang that turns its fastest piece through 1e4 rad (the thin \
             tape's: 8e3) at this step is 1.000e13"
        );
        assert!(Scene::from_toml_str(&with("solver", "bang_step_rad", "1e-4"), "t").is_ok());
    }

    #[test]
    fn too_many_samples_are_rejected() {
        // Sampling every step of a fine step over a long run.
        let text = with("solver", "max_dt_s", "1e-6") + "[output]\nsample_interval_s = 0\n";
        assert_eq!(
            err(&text),
            "output.sample_interval_s = 0: must be >= stop.max_time_s / 1e7 (= 0.000006): a run \
             may write at most 1e7 samples, and stop.max_time_s = 60 s sampled every \
             max(output.sample_interval_s, solver.max_dt_s) = 0.000001 s is 6.000e7"
        );
        let text = with("solver", "max_dt_s", "1e-6") + "[output]\nsample_interval_s = 1e-5\n";
        assert!(Scene::from_toml_str(&text, "t").is_ok());
        // The longest run allowed at the default interval is at the budget.
        assert!(Scene::from_toml_str(&with("stop", "max_time_s", "1e4"), "t").is_ok());
    }

    #[test]
    fn too_many_drawn_nodes_are_rejected() {
        // The thin tape of 1000 turns at 1000 links per turn drawn every step for 300 s: 3e5
        // drawings of 1e6 nodes.
        let fine = ["discretisation.links_per_turn=1000"];
        let msg = fails(THIN_1000, &[fine[0], "output.scene_rate_hz=1e300"]);
        assert_eq!(
            msg,
            "output.scene_rate_hz = 1e300: must be <= 1e11 / (stop.max_time_s * the tape's \
             999001 nodes) (= 333.6667), or 0 for no drawings: a run's drawings may hold at \
             most 1e11 link nodes, and stop.max_time_s = 300 s of them at \
             min(output.scene_rate_hz, 1 / solver.max_dt_s) = 1000 Hz is 2.997e11"
        );
        loads(THIN_1000, &fine);
        loads(THIN_1000, &[fine[0], "output.scene_rate_hz=0"]);
        // A rate beyond one drawing per step draws every step: the thin tape's is in budget.
        loads(THIN_1000, &["output.scene_rate_hz=1e300"]);
    }

    #[test]
    fn the_shipped_scenes_and_the_studies_stay_well_inside_every_budget() {
        let scenes = [
            (THIN_1000, vec![]),
            (THIN, vec![]),
            (YOGA, vec![]),
            // The test of an interrupted run: 6e6 steps.
            (YOGA, vec!["solver.max_dt_s=1e-5"]),
            // tools/sweeps.sh: the scaling study, the thin tape's finest resolution.
            (
                YOGA,
                vec![
                    "discretisation.links_per_turn=4096",
                    "solver.max_dt_s=0.0001",
                    "stop.max_time_s=1",
                ],
            ),
            (THIN, vec!["discretisation.links_per_turn=333"]),
            (
                THIN,
                vec![
                    "discretisation.links_per_turn=256",
                    "solver.steps_per_link=8",
                ],
            ),
        ];
        for (text, sets) in scenes {
            let s = loads(text, &sets);
            for (k, share) in shares(&s).into_iter().enumerate() {
                assert!(share <= 0.1, "{} {sets:?}: budget {k} at {share}", s.name);
            }
        }
    }
}
