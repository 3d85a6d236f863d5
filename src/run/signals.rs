//! The signals that stop a run, as a terminal or a scheduler sends them: SIGINT (Ctrl-C),
//! SIGTERM (`kill`'s default; Slurm's at a time limit, on `scancel` and on preemption,
//! before SIGKILL) and SIGHUP (the terminal closed). The first one asks the run to stop and
//! finish its files, and is named in its stop reason ([`received`]); a second one, while
//! the files are being finished, ends the process at once (exit `128 +` its number),
//! leaving the `.partial` files.

use std::fmt;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

use serde::{Deserialize, Serialize};
use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};

/// A signal that stops a run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Signal {
    /// Ctrl-C.
    #[serde(rename = "SIGINT")]
    Int,
    /// A polite kill: `kill`, a scheduler's time limit or cancel.
    #[serde(rename = "SIGTERM")]
    Term,
    /// The terminal closed.
    #[serde(rename = "SIGHUP")]
    Hup,
}

impl Signal {
    /// Every signal that stops a run.
    pub const ALL: [Self; 3] = [Self::Int, Self::Term, Self::Hup];

    /// Its number.
    pub fn number(self) -> i32 {
        match self {
            Self::Int => SIGINT,
            Self::Term => SIGTERM,
            Self::Hup => SIGHUP,
        }
    }

    /// The exit code of a process it stopped: `128 +` its number, as a shell reports one
    /// (130 for SIGINT, 143 for SIGTERM, 129 for SIGHUP).
    pub fn exit_code(self) -> u8 {
        u8::try_from(128 + self.number()).unwrap_or(u8::MAX)
    }

    fn of(number: usize) -> Option<Self> {
        Self::ALL
            .into_iter()
            .find(|s| usize::try_from(s.number()) == Ok(number))
    }
}

impl fmt::Display for Signal {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Int => "SIGINT",
            Self::Term => "SIGTERM",
            Self::Hup => "SIGHUP",
        })
    }
}

/// The number of the first stopping signal received (0: none yet).
static RECEIVED: AtomicUsize = AtomicUsize::new(0);

/// The first stopping signal this process received since [`listen`], if any.
pub fn received() -> Option<Signal> {
    Signal::of(RECEIVED.load(Ordering::SeqCst))
}

/// Installs the handlers of [`Signal::ALL`] and returns the flag the first signal raises
/// (the run's stop flag). A second signal, the flag already up, ends the process at once.
///
/// # Errors
/// If a handler cannot be installed.
pub fn listen() -> std::io::Result<Arc<AtomicBool>> {
    let stop = Arc::new(AtomicBool::new(false));
    for signal in Signal::ALL {
        let n = signal.number();
        // Handlers run in the order they were registered: the exit first (only once the
        // flag is up), then the record of which signal came, then the flag.
        signal_hook::flag::register_conditional_shutdown(
            n,
            i32::from(signal.exit_code()),
            Arc::clone(&stop),
        )?;
        signal_hook::flag::register_usize(n, &RECEIVED, usize::try_from(n).unwrap_or(0))?;
        signal_hook::flag::register(n, Arc::clone(&stop))?;
    }
    Ok(stop)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exit_codes_follow_the_shell_and_names_read_back() {
        assert_eq!(Signal::Int.exit_code(), 130);
        assert_eq!(Signal::Term.exit_code(), 143);
        assert_eq!(Signal::Hup.exit_code(), 129);
        for s in Signal::ALL {
            let json = serde_json::to_string(&s).unwrap();
            assert_eq!(json, format!("\"{s}\""));
            assert_eq!(serde_json::from_str::<Signal>(&json).unwrap(), s);
            assert_eq!(Signal::of(usize::try_from(s.number()).unwrap()), Some(s));
        }
        assert_eq!(Signal::of(0), None);
    }
}
