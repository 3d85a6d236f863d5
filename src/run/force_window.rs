//! The forces of a sample: impulses summed over a window of time and divided by it, never
//! one step's impulse over its `dt`.
//!
//! While the coil rolls, the window is the time the coil took to lay its last link (or the
//! sample interval, if longer). The chain's load sharing swings once per link laid: the
//! floor's share under the coil and the hanging link's pull trade places as the link goes
//! down, while their sum, the momentum balance, does not. A window of one link period takes that swing out and nothing else; the references
//! are evaluated at the window's mean laid fraction, so the window's half-period lag does
//! not bias a comparison. Once the coil is released the window is the sample interval.

use std::collections::VecDeque;

use crate::model::StepImpulses;

/// Running sums of the impulses on the tape, to read mean forces over a trailing window.
#[derive(Debug, Default)]
pub struct ForceWindow {
    /// `(t, impulses summed from the start, integral of the laid fraction dt)` after every
    /// step still inside the longest window that may be asked for.
    history: VecDeque<(f64, StepImpulses, f64)>,
    sum: StepImpulses,
    fraction_time: f64,
    t: f64,
    /// Times of the last two links leaving the coil (s).
    detaches: [Option<f64>; 2],
    /// Time of the last sample (s).
    sampled_at: f64,
}

/// The mean forces over a window, and where it was.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WindowMean {
    /// Mean impulse per second over the window: forces (N).
    pub forces: StepImpulses,
    /// Mean laid fraction over the window.
    pub laid_fraction: f64,
    /// Length of the window (s).
    pub span_s: f64,
}

impl ForceWindow {
    /// Adds a step of length `dt` ending at `t` with its impulses; `detached` says that a
    /// link left the coil in it.
    pub fn push(
        &mut self,
        t: f64,
        dt: f64,
        impulses: &StepImpulses,
        laid_fraction: f64,
        detached: bool,
    ) {
        if self.history.is_empty() {
            self.history
                .push_back((self.t, self.sum, self.fraction_time));
        }
        self.sum.add(impulses);
        self.fraction_time += laid_fraction * dt;
        self.t = t;
        self.history.push_back((t, self.sum, self.fraction_time));
        if detached {
            self.detaches = [self.detaches[1], Some(t)];
        }
        // Keep twice the longest window that may be asked for.
        let keep = 2.0 * (self.link_period_s().unwrap_or(0.0)).max(t - self.sampled_at);
        while self.history.len() > 2 && self.history[1].0 < t - keep {
            self.history.pop_front();
        }
    }

    /// The time the coil took to lay its last link (s), once two links have left it.
    pub fn link_period_s(&self) -> Option<f64> {
        match self.detaches {
            [Some(a), Some(b)] => Some(b - a),
            _ => None,
        }
    }

    /// The mean forces over the window ending now: one link period while `rolling` (at
    /// least the time since the last sample), else the time since the last sample. Marks
    /// now as the last sample. `None` if no time has passed.
    pub fn sample(&mut self, rolling: bool) -> Option<WindowMean> {
        let since = self.t - self.sampled_at;
        self.sampled_at = self.t;
        let span = match (rolling, self.link_period_s()) {
            (true, Some(period)) => period.max(since),
            _ => since,
        };
        if span <= 0.0 {
            return None;
        }
        // A hair inside, so that a step ending exactly one period ago starts the window.
        let (t0, sum0, ft0) = self.at(self.t - span * (1.0 - 1e-9));
        let span = self.t - t0;
        if span <= 0.0 {
            return None;
        }
        let forces = self.sum.combine(&sum0, 1.0 / span, -1.0 / span);
        Some(WindowMean {
            forces,
            laid_fraction: (self.fraction_time - ft0) / span,
            span_s: span,
        })
    }

    /// The sums after the last step ending at or before `t` (the oldest kept if none).
    fn at(&self, t: f64) -> (f64, StepImpulses, f64) {
        let i = self.history.partition_point(|h| h.0 <= t);
        self.history[i.saturating_sub(1)]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn impulse(x: f64, y: f64) -> StepImpulses {
        StepImpulses {
            total: [x, y],
            floor_on_coil: [0.5 * x, 0.5 * y],
            floor_on_moving: [x, y],
            ..StepImpulses::default()
        }
    }

    #[test]
    fn a_sample_is_the_impulses_of_its_interval_over_the_interval() {
        // Steps of uneven length: the mean force is the summed impulse over the summed
        // time, not any one step's impulse over its dt.
        let mut w = ForceWindow::default();
        let steps = [(0.001, 2.0e-3), (0.0005, 0.0), (0.0025, 1.0e-3)];
        let mut t = 0.0;
        for (dt, p) in steps {
            t += dt;
            w.push(t, dt, &impulse(p, -p), 0.2, false);
        }
        let m = w.sample(false).unwrap();
        let expected = 3.0e-3 / 0.004;
        assert!((m.forces.total[0] - expected).abs() < 1e-12, "{m:?}");
        assert!((m.forces.total[1] + expected).abs() < 1e-12);
        assert!((m.forces.floor_on_coil[0] - 0.5 * expected).abs() < 1e-12);
        assert!((m.span_s - 0.004).abs() < 1e-15);
        assert!((m.laid_fraction - 0.2).abs() < 1e-12);
        // The next sample covers only what came after this one.
        w.push(t + 0.001, 0.001, &impulse(4.0e-3, 0.0), 0.3, false);
        let m = w.sample(false).unwrap();
        assert!((m.forces.total[0] - 4.0).abs() < 1e-9, "{m:?}");
        assert!((m.laid_fraction - 0.3).abs() < 1e-12);
    }

    #[test]
    fn while_rolling_the_window_is_one_link_period_and_takes_out_a_swing_at_that_period() {
        // A force of 1 N plus a swing of 3 N at the link period, sampled every step: the
        // window of one period returns the 1 N.
        let (dt, period) = (1.0e-4, 2.0e-3);
        let mut w = ForceWindow::default();
        let mut worst: f64 = 0.0;
        for k in 1..=400 {
            let t = k as f64 * dt;
            let f = 1.0 + 3.0 * (2.0 * std::f64::consts::PI * (t - 0.5 * dt) / period).sin();
            let detached = k % 20 == 0;
            w.push(t, dt, &impulse(f * dt, 0.0), 0.5, detached);
            let m = w.sample(true).unwrap();
            if k > 60 {
                worst = worst.max((m.forces.total[0] - 1.0).abs());
                assert!((m.span_s - period).abs() < 1e-9, "span {}", m.span_s);
            }
        }
        assert!(worst < 1e-6, "the swing leaks through by {worst} N");
    }
}
