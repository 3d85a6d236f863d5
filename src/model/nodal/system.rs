//! The nodal chain's banded system: the mass matrix (softened by the rigidity's curvature),
//! the pieces' rigidity rows and the floor's contact rows, solved in time linear in the
//! pieces; and the same system for the mass matrix alone. It knows nothing of steps or
//! modes: the step (`newton.rs`) and the projection out of the floor (`contact.rs`) fill an
//! [`Assembly`] and read a [`Solution`].
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
//! are regularised by [`REGULARISATION`] of their own inverse mass. Every row of a piece is
//! taken times the piece's mass, so that a block's entries are masses or pure numbers and
//! its pivots compare with one another.

use super::{NodalChain, Piece, StepError, add, quarter, scale, sub};
use crate::model::blocks::{BlockTridiag, Singular};

/// The compliance of a contact row, relative to its own inverse effective mass: it keeps
/// the system regular where a piece's contact rows and its rigidity are redundant.
pub(super) const REGULARISATION: f64 = 1e-9;

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
    /// Empties it for a chain of `pieces`, with or without the rigidity's rows.
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
    /// Each piece's first contact row among the assembly's (one more entry than pieces).
    first_row: Vec<usize>,
    x: Vec<f64>,
}

/// Where each unknown sits in the blocks.
struct Layout<'a> {
    /// The first node with a block: 1 where node 0 is pinned.
    first: usize,
    /// 1 where the pieces' rigidity has rows.
    rigid: usize,
    first_row: &'a [usize],
}

impl Layout<'_> {
    fn rows(&self, i: usize) -> usize {
        self.first_row[i + 1] - self.first_row[i]
    }

    /// Node `k`'s block.
    fn block(&self, k: usize) -> usize {
        k - self.first
    }

    /// Node `k`'s velocity's offset in its block.
    fn vel_at(&self, k: usize) -> usize {
        if k == 0 {
            0
        } else {
            self.rigid + self.rows(k - 1)
        }
    }

    fn free(&self, k: usize) -> bool {
        k >= self.first
    }
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
    out.first_row.clear();
    let mut at = 0;
    for i in 0..pieces.len() {
        out.first_row.push(at);
        while at < a.contacts.len() && a.contacts[at].piece == i {
            at += 1;
        }
    }
    out.first_row.push(at);
    let first_row = std::mem::take(&mut out.first_row);
    let lay = Layout {
        first: usize::from(pinned),
        rigid: usize::from(a.rigid),
        first_row: &first_row,
    };
    out.sizes.clear();
    out.sizes.extend((lay.first..n).map(|k| lay.vel_at(k) + 2));
    system.reset(&out.sizes);
    fill_mass(system, pieces, a, &lay);
    for i in 0..pieces.len() {
        fill_piece(system, pieces, a, &lay, i);
    }
    // The right-hand side, in the blocks' order.
    out.x.clear();
    for k in lay.first..n {
        if k > 0 {
            let m = pieces[k - 1].mass_kg;
            if a.rigid {
                out.x.push(m * a.chord_rhs[k - 1]);
            }
            let rows = &a.contacts[first_row[k - 1]..first_row[k]];
            out.x.extend(rows.iter().map(|c| m * c.rhs));
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
    read_back(system, pieces.len(), a, &lay, out);
    out.first_row = first_row;
    Ok(())
}

/// The mass matrix, softened by the rigidity's curvature.
fn fill_mass(system: &mut BlockTridiag, pieces: &[Piece], a: &Assembly, lay: &Layout) {
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
            if !(lay.free(ka) && lay.free(kb)) {
                continue;
            }
            for (r, row) in m.iter().enumerate() {
                for (c, &v) in row.iter().enumerate() {
                    let (ra, cb) = (lay.vel_at(ka) + r, lay.vel_at(kb) + c);
                    *system.entry(lay.block(ka), ra, lay.block(kb), cb) += v;
                }
            }
        }
    }
}

/// Piece `i`'s rigidity (offset 0 of its far node's block) and contacts.
fn fill_piece(system: &mut BlockTridiag, pieces: &[Piece], a: &Assembly, lay: &Layout, i: usize) {
    let b = lay.block(i + 1);
    let m = pieces[i].mass_kg;
    if a.rigid {
        couple(system, lay, (b, 0), [(i, -1.0), (i + 1, 1.0)], |_, s| {
            (scale(-s, a.col[i]), scale(s * m, a.row[i]))
        });
    }
    let rows = &a.contacts[lay.first_row[i]..lay.first_row[i + 1]];
    for (r, c) in rows.iter().enumerate() {
        let [alpha, beta] = c.local;
        let weights = |dir: [f64; 2], node: usize| {
            let j = quarter(dir);
            if node == i {
                add(scale(1.0 - alpha, dir), scale(beta, j))
            } else {
                sub(scale(alpha, dir), scale(beta, j))
            }
        };
        let unknown = (b, lay.rigid + r);
        couple(system, lay, unknown, [(i, 0.0), (i + 1, 0.0)], |k, _| {
            (scale(-1.0, weights(c.act, k)), scale(m, weights(c.read, k)))
        });
        *system.entry(b, lay.rigid + r, b, lay.rigid + r) += m * c.reg;
    }
}

/// Puts one constraint unknown at `(block, offset)` into the system: for each of its two
/// nodes `(k, sign)`, `entries(k, sign)` gives its column in node `k`'s momentum rows and
/// its row's entries on node `k`'s velocity.
fn couple(
    system: &mut BlockTridiag,
    lay: &Layout,
    (b, o): (usize, usize),
    nodes: [(usize, f64); 2],
    entries: impl Fn(usize, f64) -> ([f64; 2], [f64; 2]),
) {
    for (k, sign) in nodes {
        if !lay.free(k) {
            continue;
        }
        let (col, row) = entries(k, sign);
        for c in 0..2 {
            *system.entry(lay.block(k), lay.vel_at(k) + c, b, o) += col[c];
            *system.entry(b, o, lay.block(k), lay.vel_at(k) + c) += row[c];
        }
    }
}

/// The unknowns, read back from the solved right-hand side.
fn read_back(system: &BlockTridiag, pieces: usize, a: &Assembly, lay: &Layout, out: &mut Solution) {
    let n = pieces + 1;
    out.delta.clear();
    out.delta.resize(n, [0.0; 2]);
    out.lambda.clear();
    out.lambda.resize(pieces, 0.0);
    out.contact.clear();
    out.contact.resize(a.contacts.len(), 0.0);
    for k in lay.first..n {
        let start = system.row_at(lay.block(k));
        if k > 0 {
            if a.rigid {
                out.lambda[k - 1] = out.x[start];
            }
            for r in 0..lay.rows(k - 1) {
                out.contact[lay.first_row[k - 1] + r] = out.x[start + lay.rigid + r];
            }
        }
        let v = start + lay.vel_at(k);
        out.delta[k] = [out.x[v], out.x[v + 1]];
    }
}

/// `M v` for the pieces' mass matrix (kg m/s per node).
pub(super) fn times_mass(pieces: &[Piece], v: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let mut out = vec![[0.0; 2]; v.len()];
    for (i, p) in pieces.iter().enumerate() {
        let [a, b, c, e] = p.mass_blocks();
        let (u, w) = (v[i], v[i + 1]);
        let near = add(scale(a, u), add(scale(c, w), scale(e, quarter(w))));
        let far = add(scale(b, w), sub(scale(c, u), scale(e, quarter(u))));
        out[i] = add(out[i], near);
        out[i + 1] = add(out[i + 1], far);
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
