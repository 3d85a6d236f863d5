//! The contacts of a stage where the tape has its thickness (a contact may join two bodies
//! far apart along the chain, which would break the joints' band), solved against the
//! chain's exact response to them by the active set of `super::active`: the joints held by
//! their own factorisation, the contacts' Delassus matrix (`super::delassus`) made a column
//! at a time, one solve of the joints' system each, the first time a contact is on, and
//! each pass one dense direct solve of the contacts that are on.
//!
//! Each contact is off, sticking (its normal and tangential relative velocities held) or
//! sliding (its normal one held, its friction `mu` times its normal impulse against the
//! slip). The modes change as `super::active` changes them, with three rules of their own:
//! a contact that arrives slipping starts by sliding; a set that cannot hold what it is
//! asked (its regularised solve answers with impulses that change velocities by far more
//! than was asked) lets its sticking contacts slide and its sliding ones stick, as an
//! impact's friction does where sliding would pull a slender piece into the surface
//! (Painleve's paradox); a contact the joints hold still is left out. Where the modes do not
//! settle the stage is left to Gauss-Seidel (`super::delassus::solve`), whose impulses
//! stay bounded. Projected Gauss-Seidel alone converged slowly on the stiff, coupled
//! contacts of tape piled on tape: on the yoga mat's bang it missed its tolerance in most
//! steps.

use super::super::{ExactChain, REGULARISATION, StepError, StepReport};
use super::active::{MAX_PASSES, Mode, Pivots, first_modes, next_mode};
use super::delassus;
use super::{Scratch, position_tolerance};

/// An impulse that would change its own velocity by more than this many times the largest
/// change the pass asked for is the regularisation's answer to a set that cannot hold it
/// (see [`solve`]): a consistent set's impulses change velocities by what was asked.
const WILD: f64 = 1e4;

/// Solves the stage's velocity, from `s.free` into `s.v`, and the candidates' impulses; its
/// iterations are its passes. `None` if the modes did not settle or a pass's system was
/// singular (nothing is kept then).
pub(super) fn solve(
    chain: &mut ExactChain,
    s: &mut Scratch,
) -> Result<Option<StepReport>, StepError> {
    let tol_speed = position_tolerance(chain) / s.h;
    let held = delassus::hold(chain, s)?;
    let held_v = s.v.clone();
    s.held.clone_from(&held_v);
    let all: Vec<usize> = (0..s.candidates.len()).collect();
    let dirs = delassus::directions(s, &all);
    let mut set = Coulomb {
        u0: dirs.iter().map(|d| d.speed(&held_v)).collect(),
        columns: vec![None; dirs.len()],
        modes: first_modes(&s.candidates),
        inert: vec![false; s.candidates.len()],
        tol_speed,
    };
    let mut pivots = Pivots::default();
    for pass in 1..=MAX_PASSES {
        set.columns_for_contacts_on(chain, s, &dirs);
        // A singular pass (sliding contacts whose friction cancels their normal's
        // response) is solved again with the contacts made compliant, a thousand and a
        // million times more than the regularisation.
        let Some(p) = [1.0, 1e3, 1e6]
            .into_iter()
            .find_map(|soft| set.impulses(s, soft * REGULARISATION))
        else {
            return Ok(None);
        };
        let broken = set.broken(s, &p);
        if broken.is_empty() {
            for (i, c) in s.candidates.iter_mut().enumerate() {
                (c.normal, c.tangent) = (p[2 * i].max(0.0), p[2 * i + 1]);
            }
            let mut v = std::mem::take(&mut s.v);
            v.clone_from(&held_v);
            let responded = delassus::respond(chain, s, &dirs, &p, held, &mut v);
            s.v = v;
            responded?;
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

/// A stage's contacts under Coulomb's law, and what is known of their Delassus matrix.
struct Coulomb {
    /// Each direction's velocity with the joints held and no contact (two a contact:
    /// normal, tangent; m/s).
    u0: Vec<f64>,
    /// The Delassus matrix's columns made so far.
    columns: Vec<Option<Vec<f64>>>,
    modes: Vec<Mode>,
    /// Contacts the joints hold still: they take nothing and ask for nothing.
    inert: Vec<bool>,
    tol_speed: f64,
}

impl Coulomb {
    /// Makes the columns of the contacts that are on; leaves out those the joints hold
    /// still, and lets those they hold still along the surface slide without friction.
    fn columns_for_contacts_on(&mut self, chain: &ExactChain, s: &Scratch, dirs: &[delassus::Dir]) {
        let need: Vec<usize> = (0..self.modes.len())
            .filter(|&i| self.modes[i] != Mode::Off)
            .flat_map(|i| [2 * i, 2 * i + 1])
            .filter(|&j| self.columns[j].is_none())
            .collect();
        for (j, column) in need.iter().zip(delassus::columns(chain, s, dirs, &need)) {
            self.columns[*j] = Some(column);
        }
        for i in 0..self.modes.len() {
            let still = |j: usize| {
                self.columns[j]
                    .as_ref()
                    .is_some_and(|c| delassus::held_still(s, &dirs[j], c[j]))
            };
            if still(2 * i) {
                self.modes[i] = Mode::Off;
                self.inert[i] = true;
            } else if self.modes[i] == Mode::Stick && still(2 * i + 1) {
                self.modes[i] = Mode::Slide(0.0);
            }
        }
    }

    /// Every direction's velocity after the impulses `p` (m/s).
    fn velocities(&self, p: &[f64]) -> Vec<f64> {
        let mut u = self.u0.clone();
        for (j, column) in self.columns.iter().enumerate() {
            if let Some(column) = column
                && p[j] != 0.0
            {
                for (ur, w) in u.iter_mut().zip(column) {
                    *ur += w * p[j];
                }
            }
        }
        u
    }

    /// The contacts the solve `p` breaks a condition of, each with the mode that mends it
    /// (`super::active`'s rules, and this module's own, see its doc).
    fn broken(&self, s: &Scratch, p: &[f64]) -> Vec<(usize, Mode)> {
        let u = self.velocities(p);
        let tol = self.tol_speed;
        let scale = (0..self.modes.len())
            .map(|i| p[2 * i].abs())
            .fold(0.0, f64::max);
        let asked = s
            .candidates
            .iter()
            .enumerate()
            .filter(|(i, _)| self.modes[*i] != Mode::Off)
            .map(|(i, c)| {
                (c.target - self.u0[2 * i])
                    .abs()
                    .max(self.u0[2 * i + 1].abs())
            })
            .fold(tol, f64::max);
        let wild = |j: usize| {
            self.columns[j]
                .as_ref()
                .is_some_and(|c| (c[j] * p[j]).abs() > WILD * asked)
        };
        let mut broken = Vec::new();
        for (i, c) in s.candidates.iter().enumerate() {
            if self.inert[i] {
                continue;
            }
            let at = [2 * i, 2 * i + 1];
            let slip = u[2 * i + 1];
            let next = match self.modes[i] {
                // Without friction the regularised problem is positive definite and its
                // pivoting settles by itself.
                Mode::Stick if c.mu > 0.0 && (wild(2 * i) || wild(2 * i + 1)) => {
                    let against = if slip.abs() > tol {
                        -slip
                    } else {
                        p[2 * i + 1]
                    };
                    Mode::Slide(against.signum())
                }
                Mode::Slide(_) if c.mu > 0.0 && wild(2 * i) => Mode::Stick,
                Mode::Off if u[2 * i] < c.target - tol && c.mu > 0.0 && slip.abs() > tol => {
                    Mode::Slide(-slip.signum())
                }
                mode => next_mode(
                    (mode, c.mu, c.target),
                    at.map(|j| p[j]),
                    at.map(|j| u[j]),
                    scale,
                    tol,
                ),
            };
            if next != self.modes[i] {
                broken.push((i, next));
            }
        }
        broken
    }

    /// The impulses along every direction (two a contact: normal, tangent) that the modes
    /// ask for: a sticking contact's relative velocity at its target normally and none
    /// tangentially, a sliding one's normal velocity at its target with its friction `mu`
    /// times its normal impulse; each equation's diagonal made `regularisation` of itself
    /// larger (a compliance). `None` where the system is singular.
    fn impulses(&self, s: &Scratch, regularisation: f64) -> Option<Vec<f64>> {
        // The unknowns: each on contact's normal impulse, and a sticking one's friction;
        // a sliding one's friction follows its normal impulse.
        let mut unknowns: Vec<(usize, Option<f64>)> = Vec::new();
        for (i, &mode) in self.modes.iter().enumerate() {
            match mode {
                Mode::Off => {}
                Mode::Stick => unknowns.extend([(2 * i, None), (2 * i + 1, None)]),
                Mode::Slide(sign) => unknowns.push((2 * i, Some(sign * s.candidates[i].mu))),
            }
        }
        let column = |j: usize| {
            self.columns[j]
                .as_ref()
                .expect("a column for each contact on")
        };
        let n = unknowns.len();
        let mut a = vec![0.0; n * n];
        let mut b = vec![0.0; n];
        // Each unknown's equation is its own direction's: the velocity along it at its
        // target (the normal's) or zero (the friction's of a sticking contact).
        for (r, &(row, _)) in unknowns.iter().enumerate() {
            let target = if row % 2 == 0 {
                s.candidates[row / 2].target
            } else {
                0.0
            };
            b[r] = target - self.u0[row];
            for (c, &(col, slide)) in unknowns.iter().enumerate() {
                let mut x = column(col)[row];
                if let Some(f) = slide {
                    x += f * column(col + 1)[row];
                }
                a[r * n + c] = x;
            }
            a[r * n + r] += regularisation * column(row)[row].abs();
        }
        let x = delassus::lu_solve(&mut a, &mut b, n)?;
        let mut p = vec![0.0; self.columns.len()];
        for (&(col, slide), &x) in unknowns.iter().zip(&x) {
            p[col] = x;
            if let Some(f) = slide {
                p[col + 1] = f * x;
            }
        }
        Some(p)
    }
}
