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
//! (Painleve's paradox); a contact the joints hold still is left out; a contact whose point
//! the joints leave one direction to move in (the pinned piece's) sticks along that
//! direction alone where its impulse went across it (see [`ONE_WAY`]). Where the modes do not
//! settle the stage is left to Gauss-Seidel (`super::delassus::solve`), whose impulses
//! stay bounded. Projected Gauss-Seidel alone converged slowly on the stiff, coupled
//! contacts of tape piled on tape: on the yoga mat's bang it missed its tolerance in most
//! steps.

use super::super::{ExactChain, REGULARISATION, StepError, StepReport};
use super::active::{MAX_PASSES, Mode, Pivots, first_modes, next_mode};
use super::delassus;
use super::modes::Candidate;
use super::{Scratch, position_tolerance};

/// An impulse that would change its own velocity by more than this many times the largest
/// change the pass asked for is the regularisation's answer to a set that cannot hold it
/// (see [`solve`]): a consistent set's impulses change velocities by what was asked.
const WILD: f64 = 1e4;

/// A contact whose two rows (normal, tangent) respond as one, the smaller eigenvalue of
/// their 2x2 block below this fraction of its normal's response with no row held, has a
/// point the joints leave one direction to move in: a point of the pinned first piece, or a
/// fold at a joint, where two pieces meet near the joint that joins them. (On the thin tape
/// such blocks' determinants measure 1e-16 to 1e-13 of their diagonal's product, and up to
/// 1e-4 where the held rows' regularisation and rounding are all that is left across the
/// direction; the others' 1e-2 or more.) An impulse across that direction moves nothing:
/// the Delassus matrix is positive semi-definite, so what is null in its own block is null
/// in all of it. Asked to stick, such a contact asks for both its rows with one direction to
/// meet them; where its targets were not exactly consistent, the solve answered with an
/// impulse across the direction bounded only by the regularisation: 121 N s on a piece of
/// 0.2 g at the thin tape's anchor, its normal and friction parts booking -0.85 J and
/// +0.85 J (b/R = 1/100 with a core, friction 1, push 0.101), and 283 N s at b/R = 1/300
/// with a core, friction 1.5, push 0.100.
///
/// So a contact of the pinned piece whose impulse goes more across its direction than along
/// it sticks along the direction alone, the pass solved again ([`Coulomb::across`]): one
/// impulse along it, the least that holds the point, answering the velocity along it;
/// beyond its friction cone it slides, as any contact does. Where the targets are consistent
/// the impulse across is rounding, and nothing changes. Three wider mends were measured and
/// dropped: every one-way contact, folds included, along its direction (the thin tape's
/// pushes stopped on the overlap guard 4-6 times in 8, against 2); sliding through the
/// impact, as the impact resolved in its own time would have such a point slide (coupled
/// one-way contacts made the sliding system singular, and a run's joints booked -400 J);
/// holding the normal velocity alone (a point moving nearly along the surface was asked
/// for a large velocity along its direction, and a run's energy rose 2.5 times its scale).
const ONE_WAY: f64 = 1e-6;

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
        one_way: vec![None; s.candidates.len()],
        along: vec![false; s.candidates.len()],
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
        if set.across(&p) {
            // The pass again, with those contacts sticking along their direction alone.
            continue;
        }
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

/// One unknown of a pass: an impulse along `impulse` (its normal and tangent parts) at
/// `contact`, and the equation it answers: the velocity along `equation` held at its target
/// (the normal's target; none along the tangent).
#[derive(Debug, Clone, Copy)]
struct Unknown {
    contact: usize,
    impulse: [f64; 2],
    equation: [f64; 2],
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
    /// The one direction a contact's point may move in, as a unit combination of its normal
    /// and tangent (its normal part `>= 0`), where the joints leave it one ([`ONE_WAY`]).
    one_way: Vec<Option<[f64; 2]>>,
    /// The one-way contacts that stick along their direction alone: those whose impulse,
    /// asked to hold both rows, went across it ([`Coulomb::across`]).
    along: Vec<bool>,
    tol_speed: f64,
}

/// Whether `c` is a contact of the pinned first piece with the floor or the laid tape: the
/// one-way contacts ([`ONE_WAY`]) this solve treats as such.
fn pinned(chain: &ExactChain, c: &Candidate) -> bool {
    chain.pin.is_some() && c.body == 0 && c.other.is_none()
}

/// The direction a contact's 2x2 block `[nn, nt, tt]` responds along, where it responds
/// along one alone ([`ONE_WAY`]; `free`, its normal's response with no row held): a unit
/// vector with its first part `>= 0`.
fn one_way([nn, nt, tt]: [f64; 3], free: f64) -> Option<[f64; 2]> {
    // The block's smaller eigenvalue, to first order in it (a determinant the rounding of
    // a held direction leaves negative is one too).
    if (nn * tt - nt * nt) / (nn + tt) > ONE_WAY * free {
        return None;
    }
    // The block's range: its larger column.
    let y = if nn >= tt { [nn, nt] } else { [nt, tt] };
    let norm = y[0].hypot(y[1]);
    let sign = if y[0] < 0.0 { -1.0 } else { 1.0 };
    (norm > 0.0).then(|| [sign * y[0] / norm, sign * y[1] / norm])
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
            } else if let (Some(n), Some(t)) = (&self.columns[2 * i], &self.columns[2 * i + 1])
                && pinned(chain, &s.candidates[i])
            {
                let free = delassus::free_response(s, &dirs[2 * i]);
                self.one_way[i] = one_way([n[2 * i], n[2 * i + 1], t[2 * i + 1]], free);
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

    /// Marks the one-way sticking contacts whose impulse in the solve `p` goes more across
    /// their direction than along it (and more than 1e-6 of the largest normal impulse), to
    /// stick along it alone ([`ONE_WAY`]); whether it marked any. Where the targets are
    /// consistent the impulse across is rounding, and the solve is left as it was.
    fn across(&mut self, p: &[f64]) -> bool {
        let scale = (0..self.modes.len())
            .map(|i| p[2 * i].abs())
            .fold(0.0, f64::max);
        let mut marked = false;
        for i in 0..self.modes.len() {
            let Some([y_n, y_t]) = self.one_way[i] else {
                continue;
            };
            if self.modes[i] != Mode::Stick || self.along[i] {
                continue;
            }
            let (p_n, p_t) = (p[2 * i], p[2 * i + 1]);
            let along = (p_n * y_n + p_t * y_t).abs();
            let across = (p_t * y_n - p_n * y_t).abs();
            if across > along.max(1e-6 * scale) {
                self.along[i] = true;
                marked = true;
            }
        }
        marked
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

    /// The unknowns the modes give: each on contact's normal impulse, and a sticking one's
    /// friction, each answering its own direction's velocity; a sliding one's friction
    /// follows its normal impulse; a sticking one-way contact ([`ONE_WAY`]) has one impulse,
    /// along its direction, answering the velocity along it.
    fn unknowns(&self, s: &Scratch) -> Vec<Unknown> {
        let mut unknowns = Vec::new();
        for (i, &mode) in self.modes.iter().enumerate() {
            let one = |impulse: [f64; 2], equation: [f64; 2]| Unknown {
                contact: i,
                impulse,
                equation,
            };
            match (mode, self.one_way[i].filter(|_| self.along[i])) {
                (Mode::Off, _) => {}
                (Mode::Stick, Some(y)) => unknowns.push(one(y, y)),
                (Mode::Stick, None) => {
                    unknowns.extend([one([1.0, 0.0], [1.0, 0.0]), one([0.0, 1.0], [0.0, 1.0])]);
                }
                (Mode::Slide(sign), _) => {
                    unknowns.push(one([1.0, sign * s.candidates[i].mu], [1.0, 0.0]));
                }
            }
        }
        unknowns
    }

    /// The impulses along every direction (two a contact: normal, tangent) that the modes
    /// ask for: a sticking contact's relative velocity at its target normally and none
    /// tangentially, a sliding one's normal velocity at its target with its friction `mu`
    /// times its normal impulse; each equation's diagonal made `regularisation` of itself
    /// larger (a compliance). `None` where the system is singular.
    fn impulses(&self, s: &Scratch, regularisation: f64) -> Option<Vec<f64>> {
        let unknowns = self.unknowns(s);
        let column = |j: usize| {
            self.columns[j]
                .as_ref()
                .expect("a column for each contact on")
        };
        // The velocity along `along` (normal, tangent parts) at contact `at` from a unit of
        // the unknown `u`.
        let response = |along: [f64; 2], at: usize, u: &Unknown| -> f64 {
            let mut x = 0.0;
            for (k, &e) in along.iter().enumerate() {
                if e == 0.0 {
                    continue;
                }
                let mut y = 0.0;
                for (m, &f) in u.impulse.iter().enumerate() {
                    if f != 0.0 {
                        y += f * column(2 * u.contact + m)[2 * at + k];
                    }
                }
                x += e * y;
            }
            x
        };
        let n = unknowns.len();
        let mut a = vec![0.0; n * n];
        let mut b = vec![0.0; n];
        for (r, row) in unknowns.iter().enumerate() {
            let i = row.contact;
            let [e_n, e_t] = row.equation;
            b[r] = e_n * (s.candidates[i].target - self.u0[2 * i]) - e_t * self.u0[2 * i + 1];
            for (c, col) in unknowns.iter().enumerate() {
                a[r * n + c] = response(row.equation, i, col);
            }
            let own = Unknown {
                impulse: row.equation,
                ..*row
            };
            a[r * n + r] += regularisation * response(row.equation, i, &own).abs();
        }
        let x = delassus::lu_solve(&mut a, &mut b, n)?;
        let mut p = vec![0.0; self.columns.len()];
        for (u, &x) in unknowns.iter().zip(&x) {
            for (m, &f) in u.impulse.iter().enumerate() {
                if f != 0.0 {
                    p[2 * u.contact + m] = f * x;
                }
            }
        }
        Some(p)
    }
}
