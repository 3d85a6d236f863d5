//! The nodal chain's step: Newton's method on the midpoint rule's equations, the floor's
//! contacts in the same iterations, each iteration one banded solve; and the same banded
//! system for the projection out of the floor and for the mass matrix alone.
//!
//! The system's block `k` holds node `k`'s unknowns after the rows of the piece before it
//! (its rigidity impulse, then its contact impulses in its points' order), so that every
//! row touches only its own block and its neighbours':
//!
//! ```text
//! block 0:  v_0                                (none where node 0 is pinned)
//! block k:  Lambda_{k-1}, P of piece k-1 ..., v_k
//! ```
//!
//! A leading set of blocks is then a sub-chain's whole system, regular wherever its
//! constraints are independent; redundant contact rows (the points of a piece lying flat)
//! are regularised by [`REGULARISATION`] of their own inverse mass.

use super::contact;
use super::{
    ContactImpulse, NodalChain, Piece, StepError, StepReport, add, cross, dot, quarter, scale, sub,
};
use crate::model::blocks::{BlockTridiag, Singular};

/// The compliance of a contact row, relative to its own inverse effective mass: it keeps
/// the system regular where a piece's contact rows and its rigidity are redundant.
pub(super) const REGULARISATION: f64 = 1e-9;

/// The step's working memory, kept from step to step.
#[derive(Debug, Default)]
pub(in crate::model) struct Scratch {
    /// Nodes and velocities at the step's start; gravity's generalised impulse `h f`.
    pub(super) x0: Vec<[f64; 2]>,
    pub(super) v0: Vec<[f64; 2]>,
    pub(super) kick: Vec<[f64; 2]>,
    /// The step's length (s).
    pub(super) h: f64,
    /// Each piece's `c_i(x) / l_i` at the step's start (m).
    c0: Vec<f64>,
    /// The iterate: end velocities, rigidity impulses (N s).
    pub(super) v: Vec<[f64; 2]>,
    lambda: Vec<f64>,
    /// The contact points' data for the step, their modes and impulses.
    pub(super) points: Vec<contact::Point>,
    pub(super) assembly: Assembly,
    pub(super) solution: Solution,
    /// The line search's iterate before the step, and the solve's impulses.
    trial: Vec<[f64; 2]>,
    trial_lambda: Vec<f64>,
    trial_impulses: Vec<[f64; 2]>,
    new_impulses: Vec<[f64; 2]>,
}

/// One contact row: the point `local` of `piece`, read along `read`, its impulse acting
/// along `act`; the row is `read . v_point + reg P = rhs`: a compliance that lets the point
/// fall short of its target by `reg P`, never pass it, so it takes energy, never gives it.
#[derive(Debug, Clone, Copy)]
pub(super) struct ContactRow {
    pub(super) piece: usize,
    pub(super) local: [f64; 2],
    pub(super) read: [f64; 2],
    pub(super) act: [f64; 2],
    pub(super) rhs: f64,
    pub(super) reg: f64,
}

/// A banded system of the chain: `K dv - sum Lambda_i col_i - C^T P = node_rhs`, with rows
/// `row_i . (dv_{i+1} - dv_i) = chord_rhs_i` where `rigid`, and the contact rows.
/// `K = M - sum soft_i H_i`, `H_i` the Hessian of `c_i` (`I` on each node, `-I` across).
#[derive(Debug, Default)]
pub(super) struct Assembly {
    pub(super) rigid: bool,
    pub(super) soft: Vec<f64>,
    pub(super) col: Vec<[f64; 2]>,
    pub(super) row: Vec<[f64; 2]>,
    pub(super) chord_rhs: Vec<f64>,
    /// Sorted by piece.
    pub(super) contacts: Vec<ContactRow>,
    pub(super) node_rhs: Vec<[f64; 2]>,
}

impl Assembly {
    pub(super) fn clear(&mut self, rigid: bool, pieces: usize) {
        self.rigid = rigid;
        self.soft.clear();
        self.soft.resize(pieces, 0.0);
        self.col.clear();
        self.row.clear();
        self.chord_rhs.clear();
        self.contacts.clear();
        self.node_rhs.clear();
    }
}

/// A solved system: each node's change, each piece's rigidity impulse, each contact row's
/// impulse.
#[derive(Debug, Default)]
pub(super) struct Solution {
    pub(super) delta: Vec<[f64; 2]>,
    pub(super) lambda: Vec<f64>,
    pub(super) contact: Vec<f64>,
    sizes: Vec<usize>,
    /// Each piece's first contact row among the assembly's.
    first_row: Vec<usize>,
    x: Vec<f64>,
}

/// The step of [`NodalChain::step`], not halved.
pub(super) fn step(
    chain: &mut NodalChain,
    h: f64,
    gravity: [f64; 2],
) -> Result<StepReport, StepError> {
    let mut s = std::mem::take(&mut chain.scratch);
    let result = iterate(chain, &mut s, h, gravity);
    chain.scratch = s;
    result
}

fn iterate(
    chain: &mut NodalChain,
    s: &mut Scratch,
    h: f64,
    gravity: [f64; 2],
) -> Result<StepReport, StepError> {
    prepare(chain, s, h, gravity);
    let kinetic0 = chain.kinetic_j();
    if chain.pieces.is_empty() {
        return Ok(StepReport {
            converged: true,
            pieces: 1,
            ..StepReport::default()
        });
    }
    let tol = chain.position_tolerance_m();
    let mut report = StepReport {
        pieces: 1,
        ..StepReport::default()
    };
    let mut phi = merit(chain, s, h);
    // Iterations in a row whose line search took less than an eighth of Newton's step.
    let mut stalled = 0;
    while report.iterations < chain.tolerance.max_iterations && stalled < STALLED {
        report.iterations += 1;
        assemble_step(chain, s, h);
        solve(
            &chain.pieces,
            chain.pinned,
            &mut chain.system,
            &s.assembly,
            &mut s.solution,
        )?;
        let widest = s
            .solution
            .delta
            .iter()
            .fold(0.0_f64, |m, d| m.max(d[0].abs().max(d[1].abs())));
        if !(widest.is_finite() && s.solution.lambda.iter().all(|x| x.is_finite())) {
            return Err(StepError::NonFinite);
        }
        let t = line_search(chain, s, h, &mut phi);
        stalled = if t < 0.125 { stalled + 1 } else { 0 };
        let settled = !contact::select(chain, s, tol / h);
        let gap = length_errors(chain, s, h);
        if settled && gap <= tol && t * h * widest <= tol {
            report.converged = true;
            break;
        }
        if !settled {
            phi = merit(chain, s, h);
        }
    }
    finish(chain, s, h, kinetic0, report)
}

/// Iterations in a row whose line search cuts Newton's step below an eighth before the step
/// is given up as stalled (and taken again in halves): the merit then sits in a valley that
/// holds no solution. On a flexing chain at 0.6 rad a step, an iteration that converges
/// does so in 3 to 7 iterations.
const STALLED: u32 = 4;

/// Takes the solve's step from the iterate, shortened by halves (down to 1/64) until it
/// lowers the merit ([`merit`]) by at least 1e-4 of its share: far from the solution (a
/// piece turning half a radian a step) the full Newton step can overshoot and cycle.
/// Returns the fraction taken; `phi` becomes the merit there.
fn line_search(chain: &NodalChain, s: &mut Scratch, h: f64, phi: &mut f64) -> f64 {
    s.trial.clone_from(&s.v);
    s.trial_lambda.clone_from(&s.lambda);
    s.trial_impulses.clear();
    s.trial_impulses.extend(s.points.iter().map(|p| p.impulse));
    contact::take_impulses(chain, s);
    s.new_impulses.clear();
    s.new_impulses.extend(s.points.iter().map(|p| p.impulse));
    let mut t = 1.0;
    loop {
        for ((v, old), d) in s.v.iter_mut().zip(&s.trial).zip(&s.solution.delta) {
            *v = add(*old, scale(t, *d));
        }
        for ((l, old), new) in s
            .lambda
            .iter_mut()
            .zip(&s.trial_lambda)
            .zip(&s.solution.lambda)
        {
            *l = old + t * (new - old);
        }
        for ((p, old), new) in s
            .points
            .iter_mut()
            .zip(&s.trial_impulses)
            .zip(&s.new_impulses)
        {
            p.impulse = [0, 1].map(|k| old[k] + t * (new[k] - old[k]));
        }
        let trial = merit(chain, s, h);
        if trial <= (1.0 - 1e-4 * t) * *phi || t <= 1.0 / 64.0 {
            *phi = trial;
            return t;
        }
        t *= 0.5;
    }
}

/// How far the iterate is from solving the step: each piece's length error, each free
/// node's momentum residual times `h` over its mass, and each contact row's miss times `h`,
/// all lengths, squared and summed (m^2).
fn merit(chain: &NodalChain, s: &mut Scratch, h: f64) -> f64 {
    let mut r = times_mass(&chain.pieces, &s.v);
    let start = times_mass(&chain.pieces, &s.v0);
    let mut mass = vec![0.0; r.len()];
    for (k, x) in r.iter_mut().enumerate() {
        *x = sub(*x, add(start[k], s.kick[k]));
    }
    let mut phi = 0.0;
    for (i, p) in chain.pieces.iter().enumerate() {
        let (mid, end) = chord_ends(s, i, h);
        let l = p.length_m;
        let pull = scale(s.lambda[i] / l, mid);
        r[i] = add(r[i], pull);
        r[i + 1] = sub(r[i + 1], pull);
        let [a, b, _, _] = p.mass_blocks();
        mass[i] += a;
        mass[i + 1] += b;
        phi += (0.5 * (dot(end, end) - l * l) / l).powi(2);
    }
    contact::subtract_forces(chain, &s.points, &mut r);
    phi += h * h * contact::row_residuals(chain, &s.points, &s.v);
    let first = usize::from(chain.pinned);
    for k in first..r.len() {
        phi += (h / mass[k]).powi(2) * dot(r[k], r[k]);
    }
    phi
}

/// The step's start: nodes, velocities, gravity's kick, the rigidity's values, the first
/// iterate (the start's velocities, last step's tension), the contacts' targets.
fn prepare(chain: &NodalChain, s: &mut Scratch, h: f64, gravity: [f64; 2]) {
    s.h = h;
    s.x0.clone_from(&chain.nodes);
    s.v0.clone_from(&chain.velocities);
    s.v.clone_from(&chain.velocities);
    s.kick.clear();
    s.kick.resize(chain.nodes.len(), [0.0; 2]);
    s.c0.clear();
    s.lambda.clear();
    for (i, p) in chain.pieces.iter().enumerate() {
        let m = p.mass_kg;
        let [alpha, beta] = p.centre;
        let (g, jg) = (gravity, quarter(gravity));
        let near = add(scale(m * (1.0 - alpha), g), scale(m * beta, jg));
        let far = sub(scale(m * alpha, g), scale(m * beta, jg));
        s.kick[i] = add(s.kick[i], scale(h, near));
        s.kick[i + 1] = add(s.kick[i + 1], scale(h, far));
        let d = sub(s.x0[i + 1], s.x0[i]);
        s.c0.push(0.5 * (dot(d, d) - p.length_m * p.length_m) / p.length_m);
        s.lambda.push(chain.tension[i] * h);
    }
    predict(chain, s, h);
    contact::prepare(chain, s, h);
}

/// The first iterate's end velocities: each piece turned rigidly at its spin as the midpoint
/// rule turns a free rotor (by `2 atan(omega h / 2)`), the nodes laid from node 0 (moved by
/// its velocity) along the turned chords. The pieces' lengths then hold from the start,
/// where the start's velocities would open them by `(omega h)^2 l / 2`.
fn predict(chain: &NodalChain, s: &mut Scratch, h: f64) {
    let mut end = add(s.x0[0], scale(h, s.v0[0]));
    s.v[0] = s.v0[0];
    for i in 0..chain.pieces.len() {
        let d = sub(s.x0[i + 1], s.x0[i]);
        let spin = cross(d, sub(s.v0[i + 1], s.v0[i])) / dot(d, d);
        let (sin, cos) = (2.0 * (0.5 * spin * h).atan()).sin_cos();
        let turned = [cos * d[0] - sin * d[1], sin * d[0] + cos * d[1]];
        end = add(end, turned);
        // x+ = x + h (v + v+) / 2.
        s.v[i + 1] = sub(scale(2.0 / h, sub(end, s.x0[i + 1])), s.v0[i + 1]);
    }
}

/// The linearised midpoint equations at the iterate, with the contacts' rows of their
/// modes.
fn assemble_step(chain: &NodalChain, s: &mut Scratch, h: f64) {
    let mut a = std::mem::take(&mut s.assembly);
    a.clear(true, chain.pieces.len());
    for (i, p) in chain.pieces.iter().enumerate() {
        let l = p.length_m;
        let (mid, end) = chord_ends(s, i, h);
        a.soft[i] = 0.25 * h * s.lambda[i] / l;
        a.col.push(scale(1.0 / l, mid));
        a.row.push(scale(1.0 / l, end));
        a.chord_rhs.push(-(dot(end, end) - l * l) / (h * l));
    }
    let momentum = times_mass(&chain.pieces, &s.v);
    let start = times_mass(&chain.pieces, &s.v0);
    for k in 0..chain.nodes.len() {
        let r = sub(add(start[k], s.kick[k]), momentum[k]);
        a.node_rhs.push(r);
    }
    contact::rows(chain, &mut s.points, &s.v, &mut a.contacts);
    s.assembly = a;
}

/// Piece `i`'s chord at the iterate's midpoint and end.
fn chord_ends(s: &Scratch, i: usize, h: f64) -> ([f64; 2], [f64; 2]) {
    let d0 = sub(s.x0[i + 1], s.x0[i]);
    let mean = |k: usize| scale(0.5, add(s.v0[k], s.v[k]));
    let dv = sub(mean(i + 1), mean(i));
    (add(d0, scale(0.5 * h, dv)), add(d0, scale(h, dv)))
}

/// The largest error of a piece's length at the iterate's end (m).
fn length_errors(chain: &NodalChain, s: &Scratch, h: f64) -> f64 {
    chain
        .pieces
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let (_, end) = chord_ends(s, i, h);
            (end[0].hypot(end[1]) - p.length_m).abs()
        })
        .fold(0.0, f64::max)
}

/// Ends the step: the nodes moved, the velocities set, the contacts recorded with their
/// work, the points below the floor moved out, the report filled in.
fn finish(
    chain: &mut NodalChain,
    s: &mut Scratch,
    h: f64,
    kinetic0: f64,
    mut report: StepReport,
) -> Result<StepReport, StepError> {
    for (k, x) in chain.nodes.iter_mut().enumerate() {
        let mean = scale(0.5, add(s.v0[k], s.v[k]));
        *x = add(s.x0[k], scale(h, mean));
    }
    chain.velocities.clone_from(&s.v);
    report.gravity_work_j = s
        .kick
        .iter()
        .zip(chain.nodes.iter().zip(&s.x0))
        .map(|(f, (x, x0))| dot(*f, sub(*x, *x0)) / h)
        .sum();
    for (i, p) in chain.pieces.iter().enumerate() {
        let d = sub(chain.nodes[i + 1], chain.nodes[i]);
        let c = 0.5 * (dot(d, d) - p.length_m * p.length_m) / p.length_m;
        report.joint_work_j += s.lambda[i] * (c - s.c0[i]) / h;
        let d0 = sub(s.x0[i + 1], s.x0[i]);
        report.max_turn_rad = report
            .max_turn_rad
            .max(cross(d0, d).atan2(dot(d0, d)).abs());
        chain.tension[i] = s.lambda[i] / h;
    }
    report.floor_work_j = contact::record(chain, s);
    report.kinetic_change_j = chain.kinetic_j() - kinetic0;
    report.joint_gap_m = chain.length_error_m();
    let (projection_j, moved) = contact::project_out(chain, s)?;
    report.projection_j = projection_j;
    report.converged &= moved;
    report.penetration_m = contact::penetration(chain, s);
    Ok(report)
}

/// Builds the banded system of `a` and solves it into `out`.
pub(super) fn solve(
    pieces: &[Piece],
    pinned: bool,
    system: &mut BlockTridiag,
    a: &Assembly,
    out: &mut Solution,
) -> Result<(), StepError> {
    let n = pieces.len() + 1;
    let first = usize::from(pinned);
    let rigid = usize::from(a.rigid);
    // Rows per piece, and where each piece's start among the contact rows.
    out.first_row.clear();
    let mut at = 0;
    for i in 0..pieces.len() {
        out.first_row.push(at);
        while at < a.contacts.len() && a.contacts[at].piece == i {
            at += 1;
        }
    }
    out.first_row.push(at);
    let rows = |i: usize| out.first_row[i + 1] - out.first_row[i];
    // Node k's block, and its velocity's offset in it.
    let block = |k: usize| k - first;
    let vel_at = |k: usize| if k == 0 { 0 } else { rigid + rows(k - 1) };
    out.sizes.clear();
    out.sizes.extend((first..n).map(|k| vel_at(k) + 2));
    system.reset(&out.sizes);
    let free = |k: usize| k >= first;
    // The mass matrix, softened by the rigidity's curvature.
    for (i, p) in pieces.iter().enumerate() {
        let [ma, mb, mc, me] = p.mass_blocks();
        let soft = a.soft[i];
        let near = [[ma - soft, 0.0], [0.0, ma - soft]];
        let far = [[mb - soft, 0.0], [0.0, mb - soft]];
        let across = [[mc + soft, -me], [me, mc + soft]];
        let back = [[mc + soft, me], [-me, mc + soft]];
        for (ka, kb, m) in [
            (i, i, near),
            (i + 1, i + 1, far),
            (i, i + 1, across),
            (i + 1, i, back),
        ] {
            if free(ka) && free(kb) {
                for (r, row) in m.iter().enumerate() {
                    for (c, &v) in row.iter().enumerate() {
                        *system.entry(block(ka), vel_at(ka) + r, block(kb), vel_at(kb) + c) += v;
                    }
                }
            }
        }
    }
    // Each piece's rigidity (offset 0 of the far node's block) and contacts.
    for i in 0..pieces.len() {
        let b = block(i + 1);
        if a.rigid {
            couple(
                system,
                (b, 0),
                [(i, -1.0), (i + 1, 1.0)],
                &free,
                &block,
                &vel_at,
                |_, s| (scale(-s, a.col[i]), scale(s, a.row[i])),
            );
        }
        for (r, c) in a.contacts[out.first_row[i]..out.first_row[i + 1]]
            .iter()
            .enumerate()
        {
            let unknown = (b, rigid + r);
            let [alpha, beta] = c.local;
            let weights = |dir: [f64; 2], node: usize| {
                let j = quarter(dir);
                if node == i {
                    add(scale(1.0 - alpha, dir), scale(beta, j))
                } else {
                    sub(scale(alpha, dir), scale(beta, j))
                }
            };
            couple(
                system,
                unknown,
                [(i, 0.0), (i + 1, 0.0)],
                &free,
                &block,
                &vel_at,
                |k, _| (scale(-1.0, weights(c.act, k)), weights(c.read, k)),
            );
            *system.entry(b, rigid + r, b, rigid + r) += c.reg;
        }
    }
    // The right-hand side, in the blocks' order.
    out.x.clear();
    for k in first..n {
        if k > 0 {
            if a.rigid {
                out.x.push(a.chord_rhs[k - 1]);
            }
            out.x.extend(
                a.contacts[out.first_row[k - 1]..out.first_row[k]]
                    .iter()
                    .map(|c| c.rhs),
            );
        }
        out.x.extend(a.node_rhs[k]);
    }
    system
        .factor()
        .map_err(|Singular { block }| StepError::Singular { block })?;
    system.solve(&mut out.x);
    if !out.x.iter().all(|x| x.is_finite()) {
        return Err(StepError::NonFinite);
    }
    // Read the unknowns back.
    out.delta.clear();
    out.delta.resize(n, [0.0; 2]);
    out.lambda.clear();
    out.lambda.resize(pieces.len(), 0.0);
    out.contact.clear();
    out.contact.resize(a.contacts.len(), 0.0);
    for k in first..n {
        let start = system.row_at(block(k));
        if k > 0 {
            if a.rigid {
                out.lambda[k - 1] = out.x[start];
            }
            for r in 0..rows(k - 1) {
                out.contact[out.first_row[k - 1] + r] = out.x[start + rigid + r];
            }
        }
        let v = start + vel_at(k);
        out.delta[k] = [out.x[v], out.x[v + 1]];
    }
    Ok(())
}

/// Puts one constraint unknown at `(block, offset)` into the system: for each of its two
/// nodes `(k, sign)`, `entries(k, sign)` gives its column in node `k`'s momentum rows and
/// its row's entries on node `k`'s velocity.
fn couple(
    system: &mut BlockTridiag,
    (b, o): (usize, usize),
    nodes: [(usize, f64); 2],
    free: &impl Fn(usize) -> bool,
    block: &impl Fn(usize) -> usize,
    vel_at: &impl Fn(usize) -> usize,
    entries: impl Fn(usize, f64) -> ([f64; 2], [f64; 2]),
) {
    for (k, sign) in nodes {
        if !free(k) {
            continue;
        }
        let (col, row) = entries(k, sign);
        for c in 0..2 {
            *system.entry(block(k), vel_at(k) + c, b, o) += col[c];
            *system.entry(b, o, block(k), vel_at(k) + c) += row[c];
        }
    }
}

/// `M v` for the pieces' mass matrix (kg m/s per node).
pub(super) fn times_mass(pieces: &[Piece], v: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let mut out = vec![[0.0; 2]; v.len()];
    for (i, p) in pieces.iter().enumerate() {
        let [a, b, c, e] = p.mass_blocks();
        let (u, w) = (v[i], v[i + 1]);
        out[i] = add(
            out[i],
            add(scale(a, u), add(scale(c, w), scale(e, quarter(w)))),
        );
        out[i + 1] = add(
            out[i + 1],
            add(scale(b, w), sub(scale(c, u), scale(e, quarter(u)))),
        );
    }
    out
}

/// The velocities whose generalised momenta `M v` are `momenta` at every free node, each
/// piece's rigidity rate held at zero: the kinetic energy's least loss from velocities
/// with those momenta, momentum and angular momentum kept (a pinned node at rest).
pub(super) fn solve_mass(
    chain: &mut NodalChain,
    momenta: &[[f64; 2]],
) -> Result<Vec<[f64; 2]>, StepError> {
    project_velocities(chain, momenta, true)
}

/// Holds node 0 at rest by an impulse there, the least kinetic energy lost.
pub(super) fn catch_first(chain: &mut NodalChain) -> Result<(), StepError> {
    let momenta = times_mass(&chain.pieces, &chain.velocities);
    chain.pinned = true;
    let caught = project_velocities(chain, &momenta, false);
    chain.pinned = false;
    chain.velocities = caught?;
    chain.velocities[0] = [0.0; 2];
    Ok(())
}

fn project_velocities(
    chain: &mut NodalChain,
    momenta: &[[f64; 2]],
    rigid: bool,
) -> Result<Vec<[f64; 2]>, StepError> {
    let mut a = Assembly::default();
    a.clear(rigid, chain.pieces.len());
    for i in 0..chain.pieces.len() {
        let d = sub(chain.nodes[i + 1], chain.nodes[i]);
        let l = chain.pieces[i].length_m;
        a.col.push(scale(1.0 / l, d));
        a.row.push(scale(1.0 / l, d));
        a.chord_rhs.push(0.0);
    }
    a.node_rhs.extend_from_slice(momenta);
    let mut out = Solution::default();
    solve(&chain.pieces, chain.pinned, &mut chain.system, &a, &mut out)?;
    Ok(out.delta)
}

/// Records the contacts' impulses of the step (see [`contact::record`]): a contact's
/// impulse as the chain reports it.
pub(super) fn contact_impulse(
    chain: &NodalChain,
    x_mid: &[[f64; 2]],
    point: &contact::Point,
    work_j: [f64; 2],
) -> ContactImpulse {
    let floor = chain.floor.expect("contacts need a floor");
    let (n, t) = (floor.normal, floor.tangent());
    let p = &chain.pieces[point.piece];
    let at = super::material(x_mid, point.piece, point.local);
    let centre = super::material(x_mid, point.piece, p.centre);
    ContactImpulse {
        piece: point.piece,
        vertex: point.vertex,
        normal_n_s: scale(point.impulse[0], n),
        friction_n_s: scale(point.impulse[1], t),
        point_m: at,
        arm_m: sub(at, centre),
        work_j,
    }
}
