//! The impulses of a stage with fewer than `super::active::FROM_CONTACTS` contact points,
//! with a contact between two bodies, or where the active set (`super::active`) did not
//! settle: the joints held by a direct solve, the contacts solved against the exact chain's
//! response by projected Gauss-Seidel on their Delassus matrix (Baraff 1996, section 8: the
//! contacts as `k` auxiliary constraints at `O(k N)`). A contact between two bodies far apart
//! along the chain would break the joints' band; as an auxiliary constraint it costs what a
//! floor's contact costs.
//!
//! The joints' rows alone are factorised once. A contact direction's response, the chain's
//! velocity change from a unit impulse along it with the joints held, is one more solve of
//! that system, and the Delassus matrix's column is that response read at the contact
//! points. Only the contacts that engage are put in it: those that pushed in the last stage,
//! and those the chain would otherwise take below their target; one that the solved motion
//! still takes below its target joins them and the contacts are solved again. Projected
//! Gauss-Seidel on the matrix (each normal impulse `>= 0` against its target, its friction
//! clamped to `mu` times it) converges on a positive semi-definite matrix, redundant contacts
//! included, with bounded impulses. A frictionless contact is its normal's direction alone:
//! a friction row clamped to zero changes nothing but the matrix's size, four times larger
//! where every contact is frictionless. The velocity is then one last solve with the contacts'
//! impulses applied.

use super::super::{ExactChain, StepError, StepReport};
use super::rows::{self, dot3};
use super::{Scratch, position_tolerance};

/// The contacts are solved when a sweep moves none of their velocities by more than this
/// fraction of the fastest of them before the stage (or by the position tolerance over the
/// step, if that is wider): the work a residual that small can do is below the ledger's
/// rounding of the bang.
pub(super) const SPEED_TOLERANCE: f64 = 1e-6;

/// The most Gauss-Seidel sweeps a stage may take.
const MAX_SWEEPS: u32 = 1000;

/// One direction a contact pushes along: its Jacobian on a body, and on a second body that
/// takes it reversed, if any. It is also the impulse's direction (`k = d`).
#[derive(Debug, Clone, Copy)]
pub(super) struct Dir {
    pub(super) body: usize,
    pub(super) d: [f64; 3],
    pub(super) other: Option<(usize, [f64; 3])>,
}

impl Dir {
    /// The velocity along it at `v` (m/s).
    pub(super) fn speed(&self, v: &[[f64; 3]]) -> f64 {
        dot3(self.d, v[self.body]) + self.other.map_or(0.0, |(o, d)| dot3(d, v[o]))
    }

    /// Its parts: each body and its Jacobian.
    fn parts(&self) -> impl Iterator<Item = (usize, [f64; 3])> {
        std::iter::once((self.body, self.d)).chain(self.other)
    }
}

/// The normal and tangent directions of the `engaged` candidates, two each, in order.
pub(super) fn directions(s: &Scratch, engaged: &[usize]) -> Vec<Dir> {
    engaged
        .iter()
        .flat_map(|&c| {
            let c = &s.candidates[c];
            [c.n, c.t()].map(|dir| {
                let (k, k_other) = c.row(dir);
                Dir {
                    body: c.body,
                    d: k,
                    other: c.other.map(|o| (o, k_other)),
                }
            })
        })
        .collect()
}

/// Solves the stage's velocity, from `s.free` into `s.v` (see the module's doc). Its
/// iterations are its sweeps; it has converged when a sweep moved no contact's velocity by
/// more than the tolerance ([`SPEED_TOLERANCE`]).
pub(super) fn solve(chain: &mut ExactChain, s: &mut Scratch) -> Result<StepReport, StepError> {
    let tol_speed = position_tolerance(chain) / s.h;
    let held = hold(chain, s)?;
    if s.candidates.is_empty() {
        return Ok(StepReport {
            iterations: 1,
            converged: true,
            ..StepReport::default()
        });
    }
    let held_v = s.v.clone();
    s.held.clone_from(&held_v);
    let speed = |s: &Scratch, c: usize, v: &[[f64; 3]]| {
        let c = &s.candidates[c];
        c.speed(c.n, v)
    };
    let mut engaged: Vec<usize> = (0..s.candidates.len())
        .filter(|&c| {
            s.candidates[c].normal > 0.0
                || speed(s, c, &held_v) < s.candidates[c].target - tol_speed
        })
        .collect();
    let mut report = StepReport::default();
    let mut p = Vec::new();
    let mut layout = Vec::new();
    for _ in 0..s.candidates.len() + 1 {
        // A frictionless contact has no friction to solve: its normal's direction alone.
        layout = rows_of(s, &engaged);
        p = engaged
            .iter()
            .zip(&layout)
            .flat_map(|(&c, (_, t))| {
                let c = &s.candidates[c];
                std::iter::once(c.normal.max(0.0)).chain(t.map(|_| c.tangent))
            })
            .collect();
        let dirs: Vec<Dir> = directions(s, &engaged)
            .into_iter()
            .enumerate()
            .filter(|(i, _)| i % 2 == 0 || layout[i / 2].1.is_some())
            .map(|(_, d)| d)
            .collect();
        if !engaged.is_empty() {
            let w = matrix(chain, s, &dirs);
            let u0: Vec<f64> = dirs.iter().map(|d| d.speed(&held_v)).collect();
            // The contacts' velocities to the position tolerance over the step, or to
            // SPEED_TOLERANCE of the fastest of them (slip included), whichever is wider.
            let slip = engaged.iter().map(|&c| {
                let c = &s.candidates[c];
                c.speed(c.t(), &held_v)
            });
            let scale = u0
                .iter()
                .copied()
                .chain(slip)
                .fold(0.0_f64, |m, x| m.max(x.abs()));
            let tol = tol_speed.max(SPEED_TOLERANCE * scale);
            let (sweeps, converged) = gauss_seidel(s, (&engaged, &layout), &w, &u0, &mut p, tol);
            report.iterations += sweeps;
            report.converged = converged;
        } else {
            report.converged = true;
        }
        let mut v = std::mem::take(&mut s.v);
        v.clear();
        v.extend_from_slice(&held_v);
        let responded = respond(chain, s, &dirs, &p, held, &mut v);
        s.v = v;
        responded?;
        let late: Vec<usize> = (0..s.candidates.len())
            .filter(|c| !engaged.contains(c))
            .filter(|&c| speed(s, c, &s.v) < s.candidates[c].target - tol_speed)
            .collect();
        if late.is_empty() {
            break;
        }
        engaged.extend(late);
        engaged.sort_unstable();
    }
    for c in &mut s.candidates {
        (c.normal, c.tangent) = (0.0, 0.0);
    }
    for (&c, &(n, t)) in engaged.iter().zip(&layout) {
        let c = &mut s.candidates[c];
        (c.normal, c.tangent) = (p[n], t.map_or(0.0, |t| p[t]));
    }
    Ok(report)
}

/// Where each of the `engaged` candidates' impulses lies among the solve's directions: its
/// normal's, and its friction's where it has friction (`mu > 0`).
fn rows_of(s: &Scratch, engaged: &[usize]) -> Vec<(usize, Option<usize>)> {
    let mut next = 0;
    engaged
        .iter()
        .map(|&c| {
            let rough = s.candidates[c].mu > 0.0;
            let at = (next, rough.then_some(next + 1));
            next += 1 + usize::from(rough);
            at
        })
        .collect()
}

/// The stage's velocity with the joints held and no contact, from `s.free` into `s.v` (the
/// joints' rows factorised in `chain.system`); whether there are joints or a pin to hold.
pub(super) fn hold(chain: &mut ExactChain, s: &mut Scratch) -> Result<bool, StepError> {
    s.base.clone_from(&s.free);
    let held = !(chain.joints.is_empty() && chain.pin.is_none());
    if held {
        rows::solve_held(chain, s)?;
        rows::apply(s);
    } else {
        s.rows.clear();
        s.v.clone_from(&s.base);
    }
    Ok(held)
}

/// Adds to `v` the velocity (or, for a move, the displacement) the impulses `p` along `dirs`
/// give, the rows of `s.rows` (factorised in `chain.system`) held against them where `held`:
/// their own kick, and one more solve for the rows' answer to it.
pub(super) fn respond(
    chain: &ExactChain,
    s: &Scratch,
    dirs: &[Dir],
    p: &[f64],
    held: bool,
    v: &mut [[f64; 3]],
) -> Result<(), StepError> {
    // The impulses alone, as a velocity change of each body.
    let mut kick = vec![[0.0; 3]; chain.bodies.len()];
    for (dir, &impulse) in dirs.iter().zip(p) {
        for (b, d) in dir.parts() {
            let w = s.inv[b];
            for k in 0..3 {
                kick[b][k] += w[k] * d[k] * impulse;
            }
        }
    }
    for (v, k) in v.iter_mut().zip(&kick) {
        for a in 0..3 {
            v[a] += k[a];
        }
    }
    if held && !s.rows.is_empty() {
        // The rows' answer to the kick: right-hand sides `-k M^-1 C^T p`.
        let mut y: Vec<f64> = s
            .rows
            .iter()
            .map(|r| {
                -(0..r.count)
                    .map(|a| dot3(r.k[a], kick[r.body[a]]))
                    .sum::<f64>()
            })
            .collect();
        chain.system.solve(&mut y);
        for (r, &x) in s.rows.iter().zip(&y) {
            for a in 0..r.count {
                let (b, d) = (r.body[a], r.d[a]);
                let w = s.inv[b];
                for k in 0..3 {
                    v[b][k] += w[k] * d[k] * x;
                }
            }
        }
    }
    if v.iter().flatten().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(StepError::NonFinite)
    }
}

/// The Delassus matrix of `dirs` (row-major, square): the velocity along each direction from
/// a unit impulse along each, the rows of `s.rows` (factorised in `chain.system`) held.
/// Each column is one solve of that system. A direction the rows hold all but still (a
/// point the pin holds, say) answers an impulse with rounding alone: its row and column are
/// zero, and it takes none.
pub(super) fn matrix(chain: &ExactChain, s: &Scratch, dirs: &[Dir]) -> Vec<f64> {
    let m = dirs.len();
    let all: Vec<usize> = (0..m).collect();
    let columns = columns(chain, s, dirs, &all);
    let mut w = vec![0.0; m * m];
    for (col, column) in columns.iter().enumerate() {
        for (row, &x) in column.iter().enumerate() {
            w[row * m + col] = x;
        }
    }
    for (i, dir) in dirs.iter().enumerate() {
        if held_still(s, dir, w[i * m + i]) {
            for j in 0..m {
                w[i * m + j] = 0.0;
                w[j * m + i] = 0.0;
            }
        }
    }
    w
}

/// Whether `dir`, whose response with the rows held is `w_ii`, is held still by them
/// ([`HELD`]).
pub(super) fn held_still(s: &Scratch, dir: &Dir, w_ii: f64) -> bool {
    w_ii <= HELD * free_response(s, dir)
}

/// The velocity along `dir` from a unit impulse along it with no row held: its bodies'
/// inverse masses along it.
pub(super) fn free_response(s: &Scratch, dir: &Dir) -> f64 {
    dir.parts()
        .map(|(b, d)| rows::weighted(d, s.inv[b], d))
        .sum()
}

/// The columns `which` of the Delassus matrix of `dirs` (see [`matrix`]), each the
/// velocity along every direction from a unit impulse along one: one solve each.
pub(super) fn columns(
    chain: &ExactChain,
    s: &Scratch,
    dirs: &[Dir],
    which: &[usize],
) -> Vec<Vec<f64>> {
    // The rows on each body a direction touches (the pin's, its two joints', a projection's
    // points): a unit impulse on a body enters the system there, and the rows' answer
    // reaches a body there.
    let mut touching: Vec<Vec<(usize, usize)>> = vec![Vec::new(); chain.bodies.len()];
    let mut listed = vec![false; chain.bodies.len()];
    for dir in dirs {
        for (b, _) in dir.parts() {
            if !listed[b] {
                listed[b] = true;
                for (i, r) in s.rows.iter().enumerate() {
                    for a in 0..r.count {
                        if r.body[a] == b {
                            touching[b].push((i, a));
                        }
                    }
                }
            }
        }
    }
    let mut bodies: Vec<usize> = dirs.iter().flat_map(|d| d.parts().map(|p| p.0)).collect();
    bodies.sort_unstable();
    bodies.dedup();
    let mut y = vec![0.0; s.rows.len()];
    let mut dv = vec![[0.0; 3]; chain.bodies.len()];
    let mut out = Vec::with_capacity(which.len());
    for &col in which {
        let dir = &dirs[col];
        y.fill(0.0);
        for (b, d) in dir.parts() {
            let inv = s.inv[b];
            let own = [inv[0] * d[0], inv[1] * d[1], inv[2] * d[2]];
            for &(i, a) in &touching[b] {
                y[i] -= dot3(s.rows[i].k[a], own);
            }
        }
        if !s.rows.is_empty() {
            chain.system.solve(&mut y);
        }
        // The response at each direction's bodies: the impulse's own kick, and the rows'
        // impulses on them.
        for &b in &bodies {
            dv[b] = [0.0; 3];
        }
        for (b, d) in dir.parts() {
            let inv = s.inv[b];
            for k in 0..3 {
                dv[b][k] += inv[k] * d[k];
            }
        }
        for &b in &bodies {
            let wb = s.inv[b];
            for &(i, a) in &touching[b] {
                let dri = s.rows[i].d[a];
                for k in 0..3 {
                    dv[b][k] += wb[k] * dri[k] * y[i];
                }
            }
        }
        out.push(dirs.iter().map(|r| r.speed(&dv)).collect());
    }
    out
}

/// A direction whose response with the rows held is below this fraction of its response
/// free is held still by them (see [`matrix`]).
const HELD: f64 = 1e-9;

/// Projected Gauss-Seidel on `w p + u0` for the `engaged` candidates: each contact's normal
/// impulse `>= 0` against its target, then its friction within `mu` times it. Returns the
/// sweeps taken and whether the last moved no contact's velocity by more than `tol_speed`.
fn gauss_seidel(
    s: &Scratch,
    (engaged, layout): (&[usize], &[(usize, Option<usize>)]),
    w: &[f64],
    u0: &[f64],
    p: &mut [f64],
    tol_speed: f64,
) -> (u32, bool) {
    let m = u0.len();
    let mut u: Vec<f64> = (0..m)
        .map(|r| u0[r] + (0..m).map(|c| w[r * m + c] * p[c]).sum::<f64>())
        .collect();
    // `w` by columns: an impulse's change moves every contact's velocity by its column,
    // read here in one run of memory (the same numbers as `w[r * m + j]`, in the same order).
    let columns: Vec<f64> = (0..m * m).map(|i| w[(i % m) * m + i / m]).collect();
    let update = |j: usize, new: f64, p: &mut [f64], u: &mut [f64]| {
        let delta = new - p[j];
        if delta != 0.0 {
            p[j] = new;
            for (ur, wr) in u.iter_mut().zip(&columns[j * m..(j + 1) * m]) {
                *ur += wr * delta;
            }
        }
        (delta * w[j * m + j]).abs()
    };
    for sweep in 1..=MAX_SWEEPS {
        let mut moved: f64 = 0.0;
        for (&c, &(n, t)) in engaged.iter().zip(layout) {
            let (target, mu) = (s.candidates[c].target, s.candidates[c].mu);
            if w[n * m + n] > 0.0 {
                let normal = (p[n] - (u[n] - target) / w[n * m + n]).max(0.0);
                moved = moved.max(update(n, normal, p, &mut u));
            }
            if let Some(t) = t
                && w[t * m + t] > 0.0
            {
                let bound = mu * p[n];
                let tangent = (p[t] - u[t] / w[t * m + t]).clamp(-bound, bound);
                moved = moved.max(update(t, tangent, p, &mut u));
            }
        }
        if moved <= tol_speed {
            return (sweep, true);
        }
    }
    (MAX_SWEEPS, false)
}

/// The least pushes `p >= 0` apart along two bodies' contacts, `w` their Delassus matrix
/// (row-major, square), that move each by `rhs` (m), or leave it further apart: every push
/// solved for at once, those that come out pulling let go and the rest solved again (a few
/// contacts, a pass or two). Redundant contacts share their push (the regularisation).
pub(super) fn push_apart(w: &[f64], rhs: &[f64]) -> Vec<f64> {
    let m = rhs.len();
    let mut on: Vec<bool> = (0..m).map(|j| w[j * m + j] > 0.0).collect();
    let mut p = vec![0.0; m];
    for _ in 0..=m {
        let idx: Vec<usize> = (0..m).filter(|&j| on[j]).collect();
        let n = idx.len();
        let mut a = vec![0.0; n * n];
        let mut b: Vec<f64> = idx.iter().map(|&j| rhs[j]).collect();
        for (r, &i) in idx.iter().enumerate() {
            for (c, &j) in idx.iter().enumerate() {
                a[r * n + c] = w[i * m + j];
            }
            a[r * n + r] += super::super::REGULARISATION * w[i * m + i];
        }
        p.fill(0.0);
        let Some(x) = lu_solve(&mut a, &mut b, n) else {
            return p;
        };
        for (&j, &x) in idx.iter().zip(&x) {
            p[j] = x;
        }
        let pulling: Vec<usize> = idx.iter().copied().filter(|&j| p[j] < 0.0).collect();
        if pulling.is_empty() {
            return p;
        }
        for j in pulling {
            on[j] = false;
        }
    }
    p.iter_mut().for_each(|x| *x = x.max(0.0));
    p
}

/// Solves `a x = b` (`a` row-major, `n` square) by Gaussian elimination with partial
/// pivoting, in place; `None` where a pivot vanishes.
pub(super) fn lu_solve(a: &mut [f64], b: &mut [f64], n: usize) -> Option<Vec<f64>> {
    let largest = a.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    for k in 0..n {
        let pivot = (k..n).max_by(|&i, &j| a[i * n + k].abs().total_cmp(&a[j * n + k].abs()))?;
        if a[pivot * n + k].abs() <= 1e-14 * largest || !a[pivot * n + k].is_finite() {
            return None;
        }
        if pivot != k {
            for c in 0..n {
                a.swap(k * n + c, pivot * n + c);
            }
            b.swap(k, pivot);
        }
        for i in k + 1..n {
            let f = a[i * n + k] / a[k * n + k];
            if f != 0.0 {
                for c in k..n {
                    a[i * n + c] -= f * a[k * n + c];
                }
                b[i] -= f * b[k];
            }
        }
    }
    let mut x = vec![0.0; n];
    for k in (0..n).rev() {
        let sum: f64 = (k + 1..n).map(|c| a[k * n + c] * x[c]).sum();
        x[k] = (b[k] - sum) / a[k * n + k];
    }
    Some(x)
}

#[cfg(test)]
mod tests {
    use super::lu_solve;

    #[test]
    fn gaussian_elimination_solves_a_system_that_needs_a_row_swap() {
        // [0 2; 3 1] x = [4; 5]: x = (1, 2); the first pivot is zero.
        let (mut a, mut b) = (vec![0.0, 2.0, 3.0, 1.0], vec![4.0, 5.0]);
        let x = lu_solve(&mut a, &mut b, 2).expect("regular");
        assert!(
            (x[0] - 1.0).abs() < 1e-15 && (x[1] - 2.0).abs() < 1e-15,
            "{x:?}"
        );
        let (mut a, mut b) = (vec![1.0, 2.0, 2.0, 4.0], vec![1.0, 2.0]);
        assert!(lu_solve(&mut a, &mut b, 2).is_none(), "singular");
    }
}
