//! The exit codes of `uncoil`, decided here and nowhere else: what each means, and how a
//! run's end maps to one. Every command returns one of these.

use std::process::ExitCode;

use uncoil::run::signals::{self, Signal};
use uncoil::run::stop::Status;

/// How `uncoil` ends.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Exit {
    /// 0: done.
    Ok,
    /// 1: a failure while running: a file that could not be read or written, a run that
    /// failed, a merge with something missing, a check that found a problem.
    Failed,
    /// 2: bad input: a scene, an argument, an output folder another run holds, files that
    /// are not of one sweep (to merge or resume), a folder that is not a killed run's (to
    /// salvage); nothing is written.
    BadInput,
    /// 3: a guard stopped a run (its outputs hold everything up to the stop).
    Stopped,
    /// `128 +` the signal's number: stopped by a signal (the outputs are finished up to the
    /// last step taken): 130 for SIGINT (Ctrl-C), 143 for SIGTERM, 129 for SIGHUP, as a
    /// shell reports a process the signal ended.
    Interrupted,
}

impl Exit {
    /// The exit of a run that ended with `status`.
    pub fn of(status: Status) -> Self {
        match status {
            Status::Completed => Self::Ok,
            Status::Interrupted => Self::Interrupted,
            Status::Stopped => Self::Stopped,
        }
    }

    /// The process's exit code.
    pub fn code(self) -> u8 {
        match self {
            Self::Ok => 0,
            Self::Failed => 1,
            Self::BadInput => 2,
            Self::Stopped => 3,
            Self::Interrupted => signals::received().unwrap_or(Signal::Int).exit_code(),
        }
    }
}

impl From<Exit> for ExitCode {
    fn from(exit: Exit) -> Self {
        ExitCode::from(exit.code())
    }
}
