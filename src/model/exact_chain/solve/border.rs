//! The contacts between two bodies (the tape's layers on each other) in the active set's
//! banded system (`super::active`), as a border: their rows would break the joints' band
//! (two bodies far apart along the chain), so the band is solved as it stands and the
//! border by its Schur complement,
//!
//! ```text
//! [A C] [x]   [a]        S = D - B A^-1 C,   S y = b - B A^-1 a,   x = A^-1 a - A^-1 C y,
//! [B D] [y] = [b]
//! ```
//!
//! `A` the band (joints, pin, the contacts on one body), `D` the border's own rows. Each
//! border row costs one more solve of the band, factorised once (`O(N)`), and `S` one dense
//! solve (`O(m^3)` in the border's rows): a stage with hundreds of contacts on the floor and
//! a few between layers is solved directly, where Gauss-Seidel on all of them
//! (`super::delassus`) took up to 1000 sweeps without converging.

use super::super::ExactChain;
use super::Scratch;
use super::delassus::lu_solve;
use super::rows::{Row, coupling};

/// The most border rows a pass may have: beyond it, the dense solve of `S` (its cube)
/// costs more than Gauss-Seidel's sweeps over all the contacts, and the stage is left to it.
pub(super) const MAX_ROWS: usize = 256;

/// Solves the border's impulses `y` against the band, whose rows (`s.rows`) are factorised
/// in `chain.system` and whose impulses without the border are in `s.x`; corrects `s.x` for
/// them. `None` where `S` is singular (nothing is changed then).
pub(super) fn solve(chain: &ExactChain, s: &mut Scratch, border: &[Row]) -> Option<Vec<f64>> {
    let m = border.len();
    if m == 0 {
        return Some(Vec::new());
    }
    let n = s.rows.len();
    // The band's rows on each body: a border row couples to those on its two bodies.
    let mut on_body: Vec<Vec<usize>> = vec![Vec::new(); chain.bodies.len()];
    for (i, r) in s.rows.iter().enumerate() {
        for a in 0..r.count {
            on_body[r.body[a]].push(i);
        }
    }
    let touched: Vec<Vec<usize>> = border
        .iter()
        .map(|r| {
            let mut t: Vec<usize> = (0..r.count)
                .flat_map(|a| on_body[r.body[a]].iter().copied())
                .collect();
            t.sort_unstable();
            t.dedup();
            t
        })
        .collect();
    // `A^-1 C`, a column per border row, and `B`'s rows where they are not zero.
    let mut z: Vec<Vec<f64>> = Vec::with_capacity(m);
    let mut b: Vec<Vec<f64>> = Vec::with_capacity(m);
    for (row, touched) in border.iter().zip(&touched) {
        let mut column = vec![0.0; n];
        for &i in touched {
            column[i] = coupling(&s.rows[i], row, &s.inv);
        }
        if n > 0 {
            chain.system.solve(&mut column);
        }
        z.push(column);
        b.push(
            touched
                .iter()
                .map(|&i| coupling(row, &s.rows[i], &s.inv))
                .collect(),
        );
    }
    let mut schur = vec![0.0; m * m];
    let mut rhs = vec![0.0; m];
    for j in 0..m {
        let bj = |v: &[f64]| -> f64 { touched[j].iter().zip(&b[j]).map(|(&i, x)| x * v[i]).sum() };
        for l in 0..m {
            schur[j * m + l] = coupling(&border[j], &border[l], &s.inv) - bj(&z[l]);
        }
        schur[j * m + j] += border[j].reg;
        rhs[j] = border[j].rhs - bj(&s.x);
    }
    let y = lu_solve(&mut schur, &mut rhs, m)?;
    for (column, &yl) in z.iter().zip(&y) {
        for (x, c) in s.x.iter_mut().zip(column) {
            *x -= c * yl;
        }
    }
    Some(y)
}

/// Adds the border's impulses `y` along its rows' directions to the iterate's velocity:
/// `v += M^-1 d^T y`.
pub(super) fn apply(s: &mut Scratch, border: &[Row], y: &[f64]) {
    for (r, &y) in border.iter().zip(y) {
        for a in 0..r.count {
            let (body, d) = (r.body[a], r.d[a]);
            let w = s.inv[body];
            for k in 0..3 {
                s.v[body][k] += w[k] * d[k] * y;
            }
        }
    }
}
