//! The rows of a step's constraints and their block-tridiagonal system: each row a
//! Jacobian `k` (what it holds) and an impulse direction `d` (along which it pushes) on one
//! or two bodies, `k M^-1 d^T x = rhs`; body `i`'s block holds the pin's rows (body 0), the
//! joint to body `i + 1` and, in a position projection, its points moved out of the floor,
//! so a joint touches two neighbouring blocks. The sets of rows (`super`'s doc):
//!
//! - the impulses at the step's start or end: joints and pin held (`G v' = 0`) at that pose
//!   (`k = d`), the contacts solved against them (`super::delassus`);
//! - the drift: each joint closed at the step's end (`g(q + h v) = 0`), its Jacobian at the
//!   iterate's predicted pose and its impulse along the start's (Newton's method, SHAKE);
//! - the projection: joints closed and points out of the floor by a move of the bodies.

use super::super::{ExactChain, REGULARISATION, StepError};
use super::Scratch;
use crate::model::blocks::Singular;

/// One row of the constraints on one or two bodies, `rhs` its target less what the base
/// velocity already gives it.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Row {
    pub(super) body: [usize; 2],
    pub(super) count: usize,
    pub(super) k: [[f64; 3]; 2],
    pub(super) d: [[f64; 3]; 2],
    pub(super) rhs: f64,
    pub(super) reg: f64,
}

/// Bodies' poses: each centre, and the cosine and sine of each angle.
#[derive(Debug, Default)]
pub(super) struct Pose {
    centre: Vec<[f64; 2]>,
    turn: Vec<[f64; 2]>,
    /// How many times it was taken: what was measured at it is known by this.
    pub(super) generation: u64,
}

impl Pose {
    /// The bodies' poses, each moved by `h` times its velocity in `v` (if given).
    pub(super) fn take(&mut self, chain: &ExactChain, v: Option<(&[[f64; 3]], f64)>) {
        self.generation += 1;
        self.centre.clear();
        self.turn.clear();
        for (i, b) in chain.bodies.iter().enumerate() {
            let (dv, h) = v.map_or(([0.0; 3], 0.0), |(v, h)| (v[i], h));
            self.centre
                .push([b.position_m[0] + h * dv[0], b.position_m[1] + h * dv[1]]);
            let (sin, cos) = (b.angle_rad + h * dv[2]).sin_cos();
            self.turn.push([cos, sin]);
        }
    }

    /// `body`'s centre of mass (world, m).
    pub(super) fn centre(&self, body: usize) -> [f64; 2] {
        self.centre[body]
    }

    /// The world offset of `local` on `body`.
    pub(super) fn arm(&self, body: usize, local: [f64; 2]) -> [f64; 2] {
        let [c, sn] = self.turn[body];
        [c * local[0] - sn * local[1], sn * local[0] + c * local[1]]
    }

    /// The world point `local` of `body`.
    pub(super) fn point(&self, body: usize, local: [f64; 2]) -> [f64; 2] {
        let a = self.arm(body, local);
        [self.centre[body][0] + a[0], self.centre[body][1] + a[1]]
    }

    /// The widest joint gap (m).
    pub(super) fn joint_gap(&self, chain: &ExactChain) -> f64 {
        let mut widest: f64 = 0.0;
        for (i, j) in chain.joints.iter().enumerate() {
            let (a, b) = (self.point(i, j.prev), self.point(i + 1, j.next));
            widest = widest.max((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2));
        }
        if let Some(pin) = chain.pin {
            let a = self.point(0, pin.anchor);
            widest = widest.max((a[0] - pin.at_m[0]).powi(2) + (a[1] - pin.at_m[1]).powi(2));
        }
        widest.sqrt()
    }
}

/// The Jacobian of the world point at offset `arm` along the world direction `dir`, per
/// unit of `(u, w, omega)`.
pub(super) fn along(dir: [f64; 2], arm: [f64; 2]) -> [f64; 3] {
    [dir[0], dir[1], arm[0] * dir[1] - arm[1] * dir[0]]
}

pub(super) fn dot3(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

pub(super) fn weighted(a: [f64; 3], w: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * w[0] * b[0] + a[1] * w[1] * b[1] + a[2] * w[2] * b[2]
}

pub(super) fn one(body: usize, k: [f64; 3], d: [f64; 3]) -> Row {
    Row {
        body: [body, 0],
        count: 1,
        k: [k, [0.0; 3]],
        d: [d, [0.0; 3]],
        rhs: 0.0,
        reg: 0.0,
    }
}

/// `k v` over the row's bodies.
fn row_dot(r: &Row, v: &[[f64; 3]]) -> f64 {
    (0..r.count).map(|a| dot3(r.k[a], v[r.body[a]])).sum()
}

/// Which stage's rows [`build`] makes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Stage {
    /// The impulses at the step's start or end (the joints' and the pin's rows; the
    /// contacts are solved against them, `super::delassus`).
    Impulses,
    /// The drift over the step (SHAKE), with the step's length.
    Drift(f64),
}

/// The rows of `stage`, block by block, their right-hand sides against `s.base` (and, for
/// the drift, the iterate `s.v`). The impulses' rows are at `s.start_pose` (at the step's
/// end, the caller has moved it there); the drift's Jacobians at `s.end_pose`. `extra` are
/// rows on one body each, in the order of their bodies, their right-hand sides already
/// against `s.base` (the contacts of `super::active`): each goes into its body's block, and
/// its place among the rows into `s.extra_at`.
pub(super) fn build(chain: &ExactChain, s: &mut Scratch, stage: Stage, extra: &[Row]) {
    s.rows.clear();
    s.sizes.clear();
    s.extra_at.clear();
    let axes = [[1.0, 0.0], [0.0, 1.0]];
    let mut next = 0;
    for i in 0..chain.bodies.len() {
        let start = s.rows.len();
        if i == 0
            && let Some(pin) = chain.pin
        {
            let a0 = s.start_pose.arm(0, pin.anchor);
            for (c, dir) in axes.into_iter().enumerate() {
                let mut row = one(0, along(dir, a0), along(dir, a0));
                if let Stage::Drift(h) = stage {
                    let a1 = s.end_pose.arm(0, pin.anchor);
                    row.k[0] = along(dir, a1);
                    let opened = pin_opened(chain, s, pin);
                    row.rhs = row_dot(&row, &s.v) - opened[c] / h;
                }
                row.rhs -= row_dot(&row, &s.base);
                s.rows.push(row);
            }
        }
        while next < extra.len() && extra[next].body[0] == i {
            s.extra_at.push(s.rows.len());
            s.rows.push(extra[next]);
            next += 1;
        }
        if i + 1 < chain.bodies.len() {
            joint_rows(chain, s, i, stage);
        }
        s.sizes.push(s.rows.len() - start);
    }
    while s.sizes.last() == Some(&0) {
        s.sizes.pop();
    }
}

/// The rows that move the bodies (no velocity) onto the joints and out of the floor and the
/// laid tape at `s.start_pose`: each joint's and the pin's gap, and each row of `deep` (body,
/// the Jacobian of its point along its normal, how far short of its place it is), by body;
/// `x` is then the move's multipliers.
pub(super) fn build_projection(
    chain: &ExactChain,
    s: &mut Scratch,
    deep: &[(usize, [f64; 3], f64)],
) {
    s.rows.clear();
    s.sizes.clear();
    let mut next = 0;
    let axes = [[1.0, 0.0], [0.0, 1.0]];
    for i in 0..chain.bodies.len() {
        let start = s.rows.len();
        if i == 0
            && let Some(pin) = chain.pin
        {
            let (a, p) = (
                s.start_pose.arm(0, pin.anchor),
                s.start_pose.point(0, pin.anchor),
            );
            for (c, dir) in axes.into_iter().enumerate() {
                let mut row = one(0, along(dir, a), along(dir, a));
                row.rhs = -(p[c] - pin.at_m[c]);
                s.rows.push(row);
            }
        }
        while next < deep.len() && deep[next].0 == i {
            let dn = deep[next].1;
            let mut row = one(i, dn, dn);
            row.rhs = deep[next].2;
            row.reg = REGULARISATION * weighted(dn, s.inv[i], dn);
            s.rows.push(row);
            next += 1;
        }
        if i + 1 < chain.bodies.len() {
            let jt = chain.joints[i];
            let (a, b) = (
                s.start_pose.arm(i, jt.prev),
                s.start_pose.arm(i + 1, jt.next),
            );
            let (pa, pb) = (
                s.start_pose.point(i, jt.prev),
                s.start_pose.point(i + 1, jt.next),
            );
            for (c, dir) in axes.into_iter().enumerate() {
                let neg = [-dir[0], -dir[1]];
                let (da, db) = (along(dir, a), along(neg, b));
                s.rows.push(Row {
                    body: [i, i + 1],
                    count: 2,
                    k: [da, db],
                    d: [da, db],
                    rhs: -(pa[c] - pb[c]),
                    reg: 0.0,
                });
            }
        }
        s.sizes.push(s.rows.len() - start);
    }
    while s.sizes.last() == Some(&0) {
        s.sizes.pop();
    }
}

/// Joint `i`'s two rows for `stage`.
fn joint_rows(chain: &ExactChain, s: &mut Scratch, i: usize, stage: Stage) {
    let jt = chain.joints[i];
    let (a0, b0) = (
        s.start_pose.arm(i, jt.prev),
        s.start_pose.arm(i + 1, jt.next),
    );
    for (c, dir) in [[1.0, 0.0], [0.0, 1.0]].into_iter().enumerate() {
        let neg = [-dir[0], -dir[1]];
        let (da, db) = (along(dir, a0), along(neg, b0));
        let mut row = Row {
            body: [i, i + 1],
            count: 2,
            k: [da, db],
            d: [da, db],
            rhs: 0.0,
            reg: 0.0,
        };
        if let Stage::Drift(h) = stage {
            let (a1, b1) = (s.end_pose.arm(i, jt.prev), s.end_pose.arm(i + 1, jt.next));
            row.k = [along(dir, a1), along(neg, b1)];
            row.rhs = row_dot(&row, &s.v) - joint_opened(chain, s, i)[c] / h;
        }
        row.rhs -= row_dot(&row, &s.base);
        s.rows.push(row);
    }
}

/// `k_r M^-1 d_c^T` over the bodies two rows share.
fn coupling(r: &Row, c: &Row, inv: &[[f64; 3]]) -> f64 {
    let mut sum = 0.0;
    for a in 0..r.count {
        let body = r.body[a];
        if c.body[0] == body {
            sum += weighted(r.k[a], inv[body], c.d[0]);
        }
        if c.count == 2 && c.body[1] == body {
            sum += weighted(r.k[a], inv[body], c.d[1]);
        }
    }
    sum
}

/// The joints held at the bodies' pose, with no contact ([`Stage::Impulses`] with no extra
/// rows), built and solved into `x` against `s.base` as [`build`] and [`solve`] would. The
/// system's factorisation is kept with the bodies' poses and masses it was made at, and a
/// later call at the same ones (the next stage's impulses at the same pose: the end of one
/// step and the start of the next, or a stage's passes) solves with it again.
pub(super) fn solve_held(chain: &mut ExactChain, s: &mut Scratch) -> Result<(), StepError> {
    build(chain, s, Stage::Impulses, &[]);
    let key = |b: &super::super::Body| {
        let [x, y] = b.position_m;
        [x, y, b.angle_rad, b.mass_kg, b.inertia_kg_m2]
    };
    if !s.held_key.is_empty() && s.held_key.iter().copied().eq(chain.bodies.iter().map(key)) {
        s.x.clear();
        s.x.extend(s.rows.iter().map(|r| r.rhs));
        chain.system.solve(&mut s.x);
        return finite(s);
    }
    solve(chain, s)?;
    s.held_key.extend(chain.bodies.iter().map(key));
    Ok(())
}

/// Whether every impulse of the solve is finite.
pub(super) fn finite(s: &Scratch) -> Result<(), StepError> {
    if s.x.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(StepError::NonFinite)
    }
}

/// Fills the block-tridiagonal system from the rows, factorises it, and solves it into `x`.
pub(super) fn solve(chain: &mut ExactChain, s: &mut Scratch) -> Result<(), StepError> {
    s.held_key.clear();
    let system = &mut chain.system;
    system.reset(&s.sizes);
    let blocks = s.sizes.len();
    for i in 0..blocks {
        let (at, size) = (system.row_at(i), system.size(i));
        let (next, next_size) = if i + 1 < blocks {
            (system.row_at(i + 1), system.size(i + 1))
        } else {
            (0, 0)
        };
        let [diag, upper, lower] = system.blocks_mut(i);
        let own = &s.rows[at..at + size];
        let others = &s.rows[next..next + next_size];
        for (r, row) in own.iter().enumerate() {
            for (c, col) in own.iter().enumerate() {
                let mut a = coupling(row, col, &s.inv);
                if r == c {
                    a += row.reg;
                }
                diag[r * size + c] = a;
            }
            // Only a row on the next body (a joint's) reaches the next block.
            if row.count == 2 {
                for (c, other) in others.iter().enumerate() {
                    upper[r * next_size + c] = coupling(row, other, &s.inv);
                    lower[c * size + r] = coupling(other, row, &s.inv);
                }
            }
        }
    }
    system
        .factor()
        .map_err(|Singular { block }| StepError::Singular { block })?;
    s.x.clear();
    s.x.extend(s.rows.iter().map(|r| r.rhs));
    system.solve(&mut s.x);
    finite(s)
}

/// The iterate's velocity from the impulses `x`: `v = v_base + M^-1 d^T x`.
pub(super) fn apply(s: &mut Scratch) {
    s.v.clone_from(&s.base);
    add_impulses(s);
}

/// The drift's right-hand sides for a chord iteration, into `s.x`: each row's gap at the
/// iterate's predicted end (`s.end_pose`) over the step, negated, in the rows' order of
/// [`build`] for [`Stage::Drift`] (the pin's, then each joint's; `x` then `y`). With the
/// factorisation of an earlier iterate, `x` solved from them is the impulses' change.
pub(super) fn drift_gaps(chain: &ExactChain, s: &mut Scratch, h: f64) {
    s.x.clear();
    if let Some(pin) = chain.pin
        && !chain.bodies.is_empty()
    {
        let opened = pin_opened(chain, s, pin);
        s.x.extend([0, 1].map(|c| -opened[c] / h));
    }
    for i in 0..chain.joints.len() {
        let opened = joint_opened(chain, s, i);
        s.x.extend([0, 1].map(|c| -opened[c] / h));
    }
    debug_assert_eq!(s.x.len(), s.rows.len(), "the drift's rows, in order");
}

/// Joint `i`'s gap at the iterate's predicted end (`s.end_pose`), by world axis (m): what
/// the drift closes. Where the steps are bounded (`ExactChain::bounded`), less its gap at
/// the step's start (`s.start_pose`): a gap the step starts with, within the position
/// tolerance (`close_joints`), is left to positions; closed by velocity it would kick the
/// bodies by gap / h, an energy that grows as the step shortens.
fn joint_opened(chain: &ExactChain, s: &Scratch, i: usize) -> [f64; 2] {
    let jt = chain.joints[i];
    let gap = |pose: &Pose| {
        let (a, b) = (pose.point(i, jt.prev), pose.point(i + 1, jt.next));
        [a[0] - b[0], a[1] - b[1]]
    };
    let end = gap(&s.end_pose);
    if !chain.bounded {
        return end;
    }
    let start = gap(&s.start_pose);
    [end[0] - start[0], end[1] - start[1]]
}

/// The pin's [`joint_opened`]: its anchor's gap from its world point at the iterate's
/// predicted end, less that at the step's start where the steps are bounded (m).
fn pin_opened(chain: &ExactChain, s: &Scratch, pin: super::super::Pin) -> [f64; 2] {
    let end = s.end_pose.point(0, pin.anchor);
    let from = if chain.bounded {
        s.start_pose.point(0, pin.anchor)
    } else {
        pin.at_m
    };
    [end[0] - from[0], end[1] - from[1]]
}

/// The widest [`joint_opened`] (and the pin's) at the iterate's predicted end (m): the
/// drift's measure of closing.
pub(super) fn widest_opened(chain: &ExactChain, s: &Scratch) -> f64 {
    let norm = |d: [f64; 2]| d[0].hypot(d[1]);
    let pin = chain
        .pin
        .filter(|_| !chain.bodies.is_empty())
        .map_or(0.0, |p| norm(pin_opened(chain, s, p)));
    (0..chain.joints.len())
        .map(|i| norm(joint_opened(chain, s, i)))
        .fold(pin, f64::max)
}

/// Adds the impulses `x` along the rows' directions to the iterate's velocity:
/// `v += M^-1 d^T x`.
pub(super) fn add_impulses(s: &mut Scratch) {
    for (r, &x) in s.rows.iter().zip(&s.x) {
        for a in 0..r.count {
            let (b, d) = (r.body[a], r.d[a]);
            let w = s.inv[b];
            for k in 0..3 {
                s.v[b][k] += w[k] * d[k] * x;
            }
        }
    }
}
