//! The floor's contacts solved with the joints in one banded system, by an active set: each
//! contact point is off, sticking (its normal and tangential velocity held) or sliding (its
//! normal velocity held, its friction `mu` times its normal impulse against the slip). A
//! contact's rows touch only its own body, so they join that body's block and the system
//! stays block-tridiagonal: each pass is one direct solve, linear in the bodies and the
//! contacts, where solving the contacts against the chain's response
//! (`super::delassus`) costs `O(k N)` to set up and `O(k^2)` a sweep. The modes start from
//! the last stage's impulses and change where a pass breaks a condition (a normal impulse
//! pulling, friction outside its cone, a slip friction would not oppose, a free point
//! going below its target); they settle in a pass or two where the contacts change little.
//! Where they do not settle within [`MAX_PASSES`], the stage is left to Gauss-Seidel.
//!
//! Several points of one rigid piece flat on the floor hold the same motion: their rows are
//! regularised by [`REGULARISATION`] of their own diagonal, so the system stays definite
//! and the impulse is shared among them.

use super::super::{ExactChain, REGULARISATION, StepError, StepReport};
use super::modes::Candidate;
use super::rows::{self, Row, Stage, dot3, one, weighted};
use super::{Scratch, position_tolerance};

/// The fewest contact points a stage must have for the active set to solve it; fewer are
/// left to Gauss-Seidel, whose `O(k N + k^2)` is then cheap. (On the thin tape, where a
/// stage has a few contacts, the active set's solutions leave the joints' work spread
/// wider over 8 pushes, -4.0 to +3.1 % of what the bang dissipates, than Gauss-Seidel's,
/// -0.3 to +3.0 %: a difference not yet explained; docs/final-bang.md.)
pub(super) const FROM_CONTACTS: usize = 64;

/// The most passes (each one direct solve) before the stage is left to Gauss-Seidel.
pub(super) const MAX_PASSES: u32 = 50;

/// Passes of block pivoting that may go without fewer contacts broken before the modes
/// change one at a time.
const STALE_PASSES: u32 = 3;

/// A normal impulse this fraction of the largest below zero lets its contact go; a friction
/// this fraction beyond its cone makes it slide.
pub(super) const SLACK: f64 = 1e-9;

/// A contact's mode in a pass.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Mode {
    Off,
    Stick,
    /// Sliding: its friction impulse `sign * mu` times its normal one.
    Slide(f64),
}

/// The modes the candidates' last impulses suggest.
pub(super) fn first_modes(candidates: &[Candidate]) -> Vec<Mode> {
    candidates
        .iter()
        .map(|c| {
            let mu = c.mu;
            if c.normal <= 0.0 {
                Mode::Off
            } else if mu > 0.0 && c.tangent.abs() < mu * c.normal * (1.0 - SLACK) {
                Mode::Stick
            } else if mu > 0.0 {
                Mode::Slide(c.tangent.signum())
            } else {
                Mode::Slide(0.0)
            }
        })
        .collect()
}

/// The mode that mends what a solve broke of a contact in `mode` (its coefficient `mu` and
/// target), given its impulses `p` and velocities `u` (normal, tangent) after the solve;
/// `scale` is the largest normal impulse of the solve, `tol_speed` the velocities'
/// tolerance. The same mode where nothing is broken: a normal impulse pulling, friction
/// outside its cone, a slip friction would not oppose, a free point going below its target.
pub(super) fn next_mode(
    (mode, mu, target): (Mode, f64, f64),
    p: [f64; 2],
    u: [f64; 2],
    scale: f64,
    tol_speed: f64,
) -> Mode {
    let [p_n, p_t] = p;
    match mode {
        Mode::Off if u[0] < target - tol_speed => {
            if mu > 0.0 {
                Mode::Stick
            } else {
                Mode::Slide(0.0)
            }
        }
        Mode::Stick | Mode::Slide(_) if p_n < -SLACK * scale => Mode::Off,
        Mode::Stick if p_t.abs() > mu * p_n * (1.0 + SLACK) + SLACK * scale => {
            Mode::Slide(p_t.signum())
        }
        Mode::Slide(sign) if sign * u[1] > tol_speed => Mode::Stick,
        mode => mode,
    }
}

/// The passes' pivoting: block pivoting (every broken contact mended at once) while the
/// number broken falls; then one at a time, the last broken (Murty's rule, which cannot
/// cycle on a frictionless floor, where the regularised matrix is positive definite).
#[derive(Default)]
pub(super) struct Pivots {
    fewest: Option<usize>,
    stale: u32,
    /// The modes of each single-pivot pass since the fewest broken last fell: met again,
    /// the passes are in a cycle that would run to MAX_PASSES (each pass repeats the one
    /// after its first visit).
    visited: Vec<Vec<Mode>>,
}

impl Pivots {
    /// Mends `broken` (each contact's index and its new mode) in `modes`, all at once or the
    /// last one alone; `false` where the passes are in a cycle (nothing is changed then).
    pub(super) fn pivot(&mut self, modes: &mut [Mode], mut broken: Vec<(usize, Mode)>) -> bool {
        if self.fewest.is_none_or(|f| broken.len() < f) {
            (self.fewest, self.stale) = (Some(broken.len()), 0);
            self.visited.clear();
        } else {
            self.stale += 1;
        }
        if self.stale >= STALE_PASSES {
            if self.visited.iter().any(|v| v == modes) {
                return false;
            }
            self.visited.push(modes.to_vec());
            broken.drain(..broken.len() - 1);
        }
        for (i, mode) in broken {
            modes[i] = mode;
        }
        true
    }
}

/// Solves the stage's velocity, from `s.free` into `s.v`, and the candidates' impulses; its
/// iterations are its passes. `None` if the modes did not settle (nothing is kept then), or
/// where a contact joins two bodies: its rows would break the band.
pub(super) fn solve(
    chain: &mut ExactChain,
    s: &mut Scratch,
) -> Result<Option<StepReport>, StepError> {
    if s.candidates.iter().any(|c| c.other.is_some()) {
        return Ok(None);
    }
    let tol_speed = position_tolerance(chain) / s.h;
    s.base.clone_from(&s.free);
    // The joints held with no contact: what the contacts' impulses act from.
    if chain.joints.is_empty() && chain.pin.is_none() {
        s.held.clone_from(&s.free);
    } else {
        rows::solve_held(chain, s)?;
        rows::apply(s);
        s.held.clone_from(&s.v);
    }
    let mut set = ActiveSet::new(s);
    let mut pivots = Pivots::default();
    for pass in 1..=MAX_PASSES {
        set.rows(s);
        rows::build(chain, s, Stage::Impulses, &set.extra);
        rows::solve(chain, s)?;
        rows::apply(s);
        let broken = set.broken(s, tol_speed);
        if broken.is_empty() {
            set.keep(s);
            return Ok(Some(StepReport {
                iterations: pass,
                converged: true,
                ..StepReport::default()
            }));
        }
        if !pivots.pivot(&mut set.modes, broken) {
            return Ok(None);
        }
    }
    Ok(None)
}

/// The candidates' modes, and the rows they give.
struct ActiveSet {
    modes: Vec<Mode>,
    /// Each candidate's first row among `extra`, if it has one.
    first: Vec<Option<usize>>,
    extra: Vec<Row>,
}

impl ActiveSet {
    /// The modes the candidates' last impulses (`s.candidates`) suggest.
    fn new(s: &Scratch) -> Self {
        Self {
            modes: first_modes(&s.candidates),
            first: vec![None; s.candidates.len()],
            extra: Vec::new(),
        }
    }

    /// The rows of the contacts that are on, in the candidates' order (their bodies').
    fn rows(&mut self, s: &Scratch) {
        self.extra.clear();
        for ((c, mode), first) in s.candidates.iter().zip(&self.modes).zip(&mut self.first) {
            let w = s.inv[c.body];
            let mu = c.mu;
            let (dn, dt) = (c.row(c.n).0, c.row(c.t()).0);
            let row = |k: [f64; 3], d: [f64; 3], target: f64| Row {
                rhs: target - dot3(k, s.base[c.body]),
                reg: REGULARISATION * weighted(k, w, k),
                ..one(c.body, k, d)
            };
            *first = (*mode != Mode::Off).then_some(self.extra.len());
            match *mode {
                Mode::Off => {}
                Mode::Stick => self.extra.extend([row(dn, dn, c.target), row(dt, dt, 0.0)]),
                Mode::Slide(sign) => {
                    let d = [0, 1, 2].map(|a| dn[a] + sign * mu * dt[a]);
                    self.extra.push(row(dn, d, c.target));
                }
            }
        }
    }

    /// Candidate `i`'s normal and friction impulses in the last solve.
    fn impulse(&self, s: &Scratch, i: usize) -> (f64, f64) {
        let Some(e) = self.first[i] else {
            return (0.0, 0.0);
        };
        let x = |e: usize| s.x[s.extra_at[e]];
        match self.modes[i] {
            Mode::Off => (0.0, 0.0),
            Mode::Stick => (x(e), x(e + 1)),
            Mode::Slide(sign) => (x(e), sign * s.candidates[i].mu * x(e)),
        }
    }

    /// The contacts the last solve breaks a condition of, each with the mode that mends it.
    fn broken(&self, s: &Scratch, tol_speed: f64) -> Vec<(usize, Mode)> {
        let scale = (0..self.modes.len())
            .map(|i| self.impulse(s, i).0.abs())
            .fold(0.0, f64::max);
        let mut broken = Vec::new();
        for (i, c) in s.candidates.iter().enumerate() {
            let (p_n, p_t) = self.impulse(s, i);
            let next = next_mode(
                (self.modes[i], c.mu, c.target),
                [p_n, p_t],
                c.speeds(&s.v),
                scale,
                tol_speed,
            );
            if next != self.modes[i] {
                broken.push((i, next));
            }
        }
        broken
    }

    /// Keeps the last solve's impulses as the candidates'.
    fn keep(&self, s: &mut Scratch) {
        for i in 0..self.modes.len() {
            let (p_n, p_t) = self.impulse(s, i);
            let c = &mut s.candidates[i];
            (c.normal, c.tangent) = (p_n.max(0.0), p_t);
        }
    }
}
