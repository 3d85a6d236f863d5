//! The exit codes of `uncoil`, decided here and nowhere else: what each means, how a run's
//! end maps to one, and which errors are bad input. Every command returns one of these.

use std::process::ExitCode;

use uncoil::output::folder::FolderError;
use uncoil::run::folded::ChainEnd;
use uncoil::run::signals::{self, Signal};
use uncoil::run::stop::Status;
use uncoil::scene::SceneError;
use uncoil::scene::overrides::OverrideSyntaxError;
use uncoil::study::check::salvage::SalvageError;
use uncoil::study::sweep::{CombinationError, NotOneSweep, SweepOutcome};

use crate::cli::paths::PathError;

/// How `uncoil` ends.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Exit {
    /// 0: done.
    Ok,
    /// 1: a failure while running: a file that could not be read or written, a run that
    /// failed, a merge with something missing, a check that found a problem.
    Failed,
    /// 2: bad input: a scene, an argument, a path that is missing or not of the kind the
    /// command expects (a folder for a file, a file for a folder, a file of another kind), an
    /// output folder another run holds, files that are not of one sweep (to merge or
    /// resume), a folder that is not a killed run's (to salvage); nothing is written.
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

    /// The exit of a folded chain's run that ended with `end`: a solve that failed or a
    /// non-finite state is a stop, as a guard's is.
    pub fn of_chain(end: ChainEnd) -> Self {
        match end {
            ChainEnd::Interrupted => Self::Interrupted,
            ChainEnd::NotFinite | ChainEnd::Unsolved => Self::Stopped,
            ChainEnd::TipFraction | ChainEnd::Rest | ChainEnd::MaxTime => Self::Ok,
        }
    }

    /// The exit of a sweep whose runs ended as `o` says: a signal first, then a failed run,
    /// then a run a guard stopped.
    pub fn of_sweep(o: &SweepOutcome) -> Self {
        if signals::received().is_some() {
            Self::Interrupted
        } else if o.failed > 0 {
            Self::Failed
        } else if o.stopped > 0 {
            Self::Stopped
        } else {
            Self::Ok
        }
    }

    /// The exit of a command that failed with `error`: [`Exit::BadInput`] when anything in
    /// its chain is an input's fault (a scene, an override, a sweep's combination, a path, an output folder another
    /// run holds, files not of one sweep, a folder that is not a killed run's), else
    /// [`Exit::Failed`].
    pub fn of_error(error: &anyhow::Error) -> Self {
        let bad = error.chain().any(|cause| {
            cause.is::<SceneError>()
                || cause.is::<OverrideSyntaxError>()
                || cause.is::<PathError>()
                || cause.is::<Usage>()
                || cause.is::<NotOneSweep>()
                || cause.is::<CombinationError>()
                || matches!(cause.downcast_ref(), Some(FolderError::Busy { .. }))
                || matches!(cause.downcast_ref(), Some(SalvageError::NotKilled(_)))
        });
        if bad { Self::BadInput } else { Self::Failed }
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

/// An argument, or a combination of them, that the command cannot take: bad input (exit 2).
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct Usage(pub String);

/// Says `error` on stderr (`error: ` and its chain) and returns its exit
/// ([`Exit::of_error`]).
pub fn fail(error: impl Into<anyhow::Error>) -> ExitCode {
    let error = error.into();
    eprintln!("error: {}", said(&error));
    Exit::of_error(&error).into()
}

/// `error` and its causes, joined by `: `, each cause said once: a cause whose text its
/// error's message already holds (`cannot read scene file x: No such file ...`) is not
/// repeated.
fn said(error: &anyhow::Error) -> String {
    let mut text = String::new();
    for cause in error.chain() {
        let part = cause.to_string();
        if text.contains(&part) {
            continue;
        }
        if !text.is_empty() {
            text.push_str(": ");
        }
        text.push_str(&part);
    }
    text
}

impl From<Exit> for ExitCode {
    fn from(exit: Exit) -> Self {
        ExitCode::from(exit.code())
    }
}
