//! Why a run stopped, typed (in the manner of argmin's `TerminationReason`): the final bang
//! at rest or at its cap, the time limit, an interruption, or a named guard with the value
//! it measured and its bound. The report, the summary, `check`, `sweep` and the exit codes
//! all read this one type; its text is its [`Display`](std::fmt::Display).

use std::fmt;

use serde::{Deserialize, Serialize};

use crate::run::guard::GuardTrip;
use crate::run::signals::Signal;

/// Why a run stopped.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "reason", rename_all = "kebab-case")]
pub enum StopReason {
    /// The final bang came to rest: at most `stop.rest_fraction` of the kinetic energy it
    /// received was still moving.
    AtRest {
        /// When (s).
        t_s: f64,
        /// The kinetic energy still moving, over what the bang received.
        still_moving: f64,
        /// The scene's `stop.rest_fraction`.
        rest_fraction: f64,
    },
    /// The final bang reached `stop.bang_cap_s` before it came to rest.
    BangCap {
        /// When (s).
        t_s: f64,
        /// The kinetic energy still moving, over what the bang received.
        still_moving: f64,
        /// The scene's `stop.bang_cap_s` (s).
        bang_cap_s: f64,
    },
    /// `stop.max_time_s` was reached before the bang ended.
    MaxTime {
        /// When (s).
        t_s: f64,
        /// The scene's `stop.max_time_s` (s).
        max_time_s: f64,
    },
    /// The run was asked to stop (a signal, or Python's Ctrl-C); its outputs end at the last
    /// step taken.
    Interrupted {
        /// When (s).
        t_s: f64,
        /// The signal that asked, where one did.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        signal: Option<Signal>,
    },
    /// A guard stopped the run.
    Guard(GuardTrip),
}

/// How a run ended, in three kinds: what the exit code and a sweep's status tell apart.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Status {
    /// The run ended as planned: the bang ended (at rest or at its cap), or the time limit
    /// was reached.
    Completed,
    /// The run was asked to stop before its end.
    Interrupted,
    /// A guard stopped the run.
    Stopped,
}

impl StopReason {
    /// The kind of ending.
    pub fn status(&self) -> Status {
        match self {
            Self::AtRest { .. } | Self::BangCap { .. } | Self::MaxTime { .. } => Status::Completed,
            Self::Interrupted { .. } => Status::Interrupted,
            Self::Guard(_) => Status::Stopped,
        }
    }

    /// The guard that stopped the run, if one did.
    pub fn guard(&self) -> Option<&GuardTrip> {
        match self {
            Self::Guard(trip) => Some(trip),
            _ => None,
        }
    }
}

impl fmt::Display for StopReason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::AtRest {
                still_moving,
                rest_fraction,
                ..
            } => write!(
                f,
                "the final bang came to rest: {:.3} % of the kinetic energy it received still \
                 moving (stop.rest_fraction = {rest_fraction})",
                100.0 * still_moving
            ),
            Self::BangCap {
                still_moving,
                bang_cap_s,
                ..
            } => write!(
                f,
                "the final bang reached its cap, stop.bang_cap_s = {bang_cap_s} s, with {:.3} % \
                 of the kinetic energy it received still moving",
                100.0 * still_moving
            ),
            Self::MaxTime { max_time_s, .. } => write!(f, "stop.max_time_s = {max_time_s} reached"),
            Self::Interrupted {
                signal: Some(signal),
                ..
            } => write!(f, "interrupted by {signal}"),
            Self::Interrupted { signal: None, .. } => f.write_str("interrupted"),
            Self::Guard(trip) => trip.fmt(f),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::run::guard::GuardKind;

    #[test]
    fn a_guard_stop_is_stopped_and_reads_back_from_json() {
        let stop = StopReason::Guard(GuardTrip {
            guard: GuardKind::JointGap,
            t_s: 0.074,
            value: 0.02,
            bound: 0.005,
        });
        assert_eq!(stop.status(), Status::Stopped);
        let json = serde_json::to_string(&stop).unwrap();
        assert!(json.contains("\"reason\":\"guard\""), "{json}");
        assert!(json.contains("\"guard\":\"joint-gap\""), "{json}");
        let back: StopReason = serde_json::from_str(&json).unwrap();
        assert_eq!(back, stop);
        assert!(
            stop.to_string()
                .starts_with("joints separating at t = 0.074000 s")
        );
    }

    #[test]
    fn the_ends_as_planned_are_completed_and_an_interruption_is_not() {
        let rest = StopReason::AtRest {
            t_s: 2.4,
            still_moving: 1.7e-4,
            rest_fraction: 1e-3,
        };
        let max = StopReason::MaxTime {
            t_s: 1.0,
            max_time_s: 1.0,
        };
        assert_eq!(rest.status(), Status::Completed);
        assert_eq!(max.status(), Status::Completed);
        assert_eq!(
            StopReason::Interrupted {
                t_s: 0.1,
                signal: None
            }
            .status(),
            Status::Interrupted
        );
        assert_eq!(
            rest.to_string(),
            "the final bang came to rest: 0.017 % of the kinetic energy it received still moving (stop.rest_fraction = 0.001)"
        );
    }
}
