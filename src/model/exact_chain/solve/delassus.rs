//! The impulses of a stage with fewer than `super::active::FROM_CONTACTS` contact points, or
//! where the active set (`super::active`) did not settle: the joints
//! held by a direct solve, the floor's contacts solved against the exact chain's response by
//! projected Gauss-Seidel on their Delassus matrix (Baraff 1996, section 8: the contacts as
//! `k` auxiliary constraints at `O(k N)`).
//!
//! The joints' rows alone are factorised once. A contact direction's response, the chain's
//! velocity change from a unit impulse along it with the joints held, is one more solve of
//! that system, and the Delassus matrix's column is that response read at the contact
//! points. Only the contacts that engage are put in it: those that pushed in the last stage,
//! and those the chain would otherwise take below their target; one that the solved motion
//! still takes below its target joins them and the contacts are solved again. Projected
//! Gauss-Seidel on the matrix (each normal impulse `>= 0` against its target, its friction
//! clamped to `mu` times it) converges on a positive semi-definite matrix, redundant contacts
//! included, with bounded impulses. The velocity is then one last solve with the contacts'
//! impulses applied.

use super::super::{ExactChain, StepError, StepReport};
use super::rows::{self, along, dot3};
use super::{Scratch, position_tolerance};

/// The contacts are solved when a sweep moves none of their velocities by more than this
/// fraction of the fastest of them before the stage (or by the position tolerance over the
/// step, if that is wider): the work a residual that small can do is below the ledger's
/// rounding of the bang.
pub(super) const SPEED_TOLERANCE: f64 = 1e-6;

/// The most Gauss-Seidel sweeps a stage may take.
const MAX_SWEEPS: u32 = 1000;

/// Solves the stage's velocity, from `s.free` into `s.v` (see the module's doc). Its
/// iterations are its sweeps; it has converged when a sweep moved no contact's velocity by
/// more than the tolerance ([`SPEED_TOLERANCE`]).
pub(super) fn solve(chain: &mut ExactChain, s: &mut Scratch) -> Result<StepReport, StepError> {
    let tol_speed = position_tolerance(chain) / s.h;
    s.base.clone_from(&s.free);
    let held = !(chain.joints.is_empty() && chain.pin.is_none());
    if held {
        rows::solve_held(chain, s)?;
        rows::apply(s);
    } else {
        s.rows.clear();
        s.v.clone_from(&s.base);
    }
    let floor = chain.floor;
    let Some(floor) = floor.filter(|_| !s.candidates.is_empty()) else {
        return Ok(StepReport {
            iterations: 1,
            converged: true,
            ..StepReport::default()
        });
    };
    let held_v = s.v.clone();
    s.held.clone_from(&held_v);
    let speed = |s: &Scratch, c: usize, v: &[[f64; 3]]| {
        let c = &s.candidates[c];
        dot3(along(floor.normal, c.arm), v[c.body])
    };
    let mut engaged: Vec<usize> = (0..s.candidates.len())
        .filter(|&c| {
            s.candidates[c].normal > 0.0
                || speed(s, c, &held_v) < s.candidates[c].target - tol_speed
        })
        .collect();
    let mut report = StepReport::default();
    let mut p = Vec::new();
    for _ in 0..s.candidates.len() + 1 {
        p = engaged
            .iter()
            .flat_map(|&c| [s.candidates[c].normal.max(0.0), s.candidates[c].tangent])
            .collect();
        if !engaged.is_empty() {
            let (w, u0) = delassus(chain, s, &engaged, &held_v);
            // The contacts' velocities to the position tolerance over the step, or to
            // SPEED_TOLERANCE of the fastest of them, whichever is wider.
            let scale = u0.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
            let tol = tol_speed.max(SPEED_TOLERANCE * scale);
            let (sweeps, converged) = gauss_seidel(chain, s, &engaged, &w, &u0, &mut p, tol);
            report.iterations += sweeps;
            report.converged = converged;
        } else {
            report.converged = true;
        }
        apply_contacts(chain, s, &engaged, &p, &held_v, held)?;
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
    for (i, &c) in engaged.iter().enumerate() {
        let c = &mut s.candidates[c];
        (c.normal, c.tangent) = (p[2 * i], p[2 * i + 1]);
    }
    Ok(report)
}

/// The velocity `s.v` from `held` (the joints held, no contact) and the contacts' impulses
/// `p` of the `engaged` candidates, the joints held against them: one more solve.
fn apply_contacts(
    chain: &ExactChain,
    s: &mut Scratch,
    engaged: &[usize],
    p: &[f64],
    held: &[[f64; 3]],
    joints: bool,
) -> Result<(), StepError> {
    let floor = chain.floor.expect("contacts need a floor");
    // The contacts' impulses alone, as a velocity change of each body.
    let mut kick = vec![[0.0; 3]; chain.bodies.len()];
    for (i, &c) in engaged.iter().enumerate() {
        let c = &s.candidates[c];
        let w = s.inv[c.body];
        for (dir, impulse) in [(floor.normal, p[2 * i]), (floor.tangent(), p[2 * i + 1])] {
            let d = along(dir, c.arm);
            for k in 0..3 {
                kick[c.body][k] += w[k] * d[k] * impulse;
            }
        }
    }
    s.v.clear();
    s.v.extend_from_slice(held);
    for (v, k) in s.v.iter_mut().zip(&kick) {
        for a in 0..3 {
            v[a] += k[a];
        }
    }
    if joints {
        // The joints' answer to the kick: rows' right-hand sides `-k M^-1 C^T p`.
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
                    s.v[b][k] += w[k] * d[k] * x;
                }
            }
        }
    }
    if s.v.iter().flatten().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(StepError::NonFinite)
    }
}

/// The Delassus matrix of the `engaged` candidates (row-major, `2k` square: each contact's
/// normal then tangent) and their velocities with the joints held and no contact, `u0`.
/// Each column is one solve of the joints' factorised system (`chain.system`).
fn delassus(
    chain: &ExactChain,
    s: &Scratch,
    engaged: &[usize],
    held: &[[f64; 3]],
) -> (Vec<f64>, Vec<f64>) {
    let floor = chain.floor.expect("candidates need a floor");
    let dirs: Vec<(usize, [f64; 3])> = engaged
        .iter()
        .flat_map(|&c| {
            let c = &s.candidates[c];
            [floor.normal, floor.tangent()].map(|dir| (c.body, along(dir, c.arm)))
        })
        .collect();
    let m = dirs.len();
    let mut w = vec![0.0; m * m];
    // The rows on each engaged body (the pin's, its two joints'): a unit impulse on a body
    // enters the system there, and the joints' answer reaches a body there.
    let mut touching: Vec<Vec<(usize, usize)>> = vec![Vec::new(); chain.bodies.len()];
    for &(b, _) in &dirs {
        if touching[b].is_empty() {
            for (i, r) in s.rows.iter().enumerate() {
                for a in 0..r.count {
                    if r.body[a] == b {
                        touching[b].push((i, a));
                    }
                }
            }
        }
    }
    let mut y = vec![0.0; s.rows.len()];
    for (col, &(body, d)) in dirs.iter().enumerate() {
        let inv = s.inv[body];
        let own = [inv[0] * d[0], inv[1] * d[1], inv[2] * d[2]];
        y.fill(0.0);
        for &(i, a) in &touching[body] {
            y[i] = -dot3(s.rows[i].k[a], own);
        }
        if !s.rows.is_empty() {
            chain.system.solve(&mut y);
        }
        // The response at each contact's body: its own kick, and the joints' impulses on it.
        for (row, &(b, dr)) in dirs.iter().enumerate() {
            let mut dv = if b == body { own } else { [0.0; 3] };
            let wb = s.inv[b];
            for &(i, a) in &touching[b] {
                let dri = s.rows[i].d[a];
                for k in 0..3 {
                    dv[k] += wb[k] * dri[k] * y[i];
                }
            }
            w[row * m + col] = dot3(dr, dv);
        }
    }
    let u0 = dirs.iter().map(|&(b, d)| dot3(d, held[b])).collect();
    (w, u0)
}

/// Projected Gauss-Seidel on `w p + u0` for the `engaged` candidates: each contact's normal
/// impulse `>= 0` against its target, then its friction within `mu` times it. Returns the
/// sweeps taken and whether the last moved no contact's velocity by more than `tol_speed`.
fn gauss_seidel(
    chain: &ExactChain,
    s: &Scratch,
    engaged: &[usize],
    w: &[f64],
    u0: &[f64],
    p: &mut [f64],
    tol_speed: f64,
) -> (u32, bool) {
    let mu = chain.floor.map_or(0.0, |f| f.friction);
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
        for (i, &c) in engaged.iter().enumerate() {
            let target = s.candidates[c].target;
            let (n, t) = (2 * i, 2 * i + 1);
            if w[n * m + n] > 0.0 {
                let normal = (p[n] - (u[n] - target) / w[n * m + n]).max(0.0);
                moved = moved.max(update(n, normal, p, &mut u));
            }
            if w[t * m + t] > 0.0 {
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
