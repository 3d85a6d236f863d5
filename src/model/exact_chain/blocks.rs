//! A block-tridiagonal linear system solved exactly by block LU (block Thomas), in time
//! linear in its number of blocks: each diagonal block a small dense matrix factorised with
//! partial pivoting, no iteration count. It knows nothing of chains or contacts.
//!
//! ```text
//! | D_0 U_0             | | x_0 |   | b_0 |
//! | L_1 D_1 U_1         | | x_1 |   | b_1 |
//! |     L_2 D_2 U_2     | | x_2 | = | b_2 |
//! |         ...         | | ... |   | ... |
//! ```
//!
//! Forward: `D_i <- D_i - L_i D_{i-1}^-1 U_{i-1}`, `b_i <- b_i - L_i D_{i-1}^-1 b_{i-1}`;
//! back: `x_i = D_i^-1 b_i - D_i^-1 U_i x_{i+1}`.

/// A pivot smaller than this fraction of its block's largest entry means a singular system.
const SINGULAR: f64 = 1e-13;

/// The system's blocks, reused from solve to solve (nothing is allocated once grown).
#[derive(Debug, Default)]
pub(super) struct BlockTridiag {
    sizes: Vec<usize>,
    /// First unknown of each block.
    row_at: Vec<usize>,
    diag_at: Vec<usize>,
    /// Offset of `U_i` (block i by block i + 1), and of `L_{i+1}` (block i + 1 by block i).
    off_at: Vec<usize>,
    diag: Vec<f64>,
    upper: Vec<f64>,
    lower: Vec<f64>,
    pivots: Vec<usize>,
    /// One row of products, the widest block's.
    work: Vec<f64>,
}

/// The system could not be solved: block `block`'s pivot vanished.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Singular {
    pub(super) block: usize,
}

impl BlockTridiag {
    /// Sets the block sizes and zeroes every block.
    pub(super) fn reset(&mut self, sizes: &[usize]) {
        self.sizes.clear();
        self.sizes.extend_from_slice(sizes);
        self.row_at.clear();
        self.diag_at.clear();
        self.off_at.clear();
        let (mut row, mut diag, mut off) = (0, 0, 0);
        for (i, &s) in sizes.iter().enumerate() {
            self.row_at.push(row);
            self.diag_at.push(diag);
            self.off_at.push(off);
            row += s;
            diag += s * s;
            off += s * sizes.get(i + 1).copied().unwrap_or(0);
        }
        self.row_at.push(row);
        self.diag.clear();
        self.diag.resize(diag, 0.0);
        self.upper.clear();
        self.upper.resize(off, 0.0);
        self.lower.clear();
        self.lower.resize(off, 0.0);
        self.pivots.clear();
        self.pivots.resize(row, 0);
        let widest = sizes.iter().copied().max().unwrap_or(0);
        self.work.clear();
        self.work.resize(widest, 0.0);
    }

    /// Block `i`'s first unknown.
    pub(super) fn row_at(&self, i: usize) -> usize {
        self.row_at[i]
    }

    /// Block `i`'s size.
    pub(super) fn size(&self, i: usize) -> usize {
        self.sizes[i]
    }

    /// The entry at `(r, c)` within diagonal block `i`.
    pub(super) fn diag_mut(&mut self, i: usize, r: usize, c: usize) -> &mut f64 {
        let s = self.sizes[i];
        &mut self.diag[self.diag_at[i] + r * s + c]
    }

    /// The entry at `(r, c)` of `U_i`: row `r` of block `i`, column `c` of block `i + 1`.
    pub(super) fn upper_mut(&mut self, i: usize, r: usize, c: usize) -> &mut f64 {
        let s = self.sizes[i + 1];
        &mut self.upper[self.off_at[i] + r * s + c]
    }

    /// The entry at `(r, c)` of `L_{i+1}`: row `r` of block `i + 1`, column `c` of block `i`.
    pub(super) fn lower_mut(&mut self, i: usize, r: usize, c: usize) -> &mut f64 {
        let s = self.sizes[i];
        &mut self.lower[self.off_at[i] + r * s + c]
    }

    /// Factorises the system and solves it for `b`, which becomes the solution. The blocks
    /// are overwritten: `reset` and fill them again before the next solve.
    pub(super) fn solve(&mut self, b: &mut [f64]) -> Result<(), Singular> {
        let n = self.sizes.len();
        for i in 0..n {
            if i > 0 {
                self.eliminate_lower(i, b);
            }
            let (s, at, row) = (self.sizes[i], self.diag_at[i], self.row_at[i]);
            let block = &mut self.diag[at..at + s * s];
            lu_factor(block, s, &mut self.pivots[row..row + s])
                .map_err(|()| Singular { block: i })?;
            let block = &self.diag[at..at + s * s];
            let pivots = &self.pivots[row..row + s];
            lu_solve(block, s, pivots, &mut b[row..row + s], 1);
            if i + 1 < n {
                // U_i becomes D_i^-1 U_i.
                let (s1, off) = (self.sizes[i + 1], self.off_at[i]);
                lu_solve(block, s, pivots, &mut self.upper[off..off + s * s1], s1);
            }
        }
        for i in (0..n.saturating_sub(1)).rev() {
            let (s, s1, off) = (self.sizes[i], self.sizes[i + 1], self.off_at[i]);
            let (row, next) = (self.row_at[i], self.row_at[i + 1]);
            for r in 0..s {
                let w = &self.upper[off + r * s1..off + (r + 1) * s1];
                let dot: f64 = w.iter().zip(&b[next..next + s1]).map(|(a, x)| a * x).sum();
                b[row + r] -= dot;
            }
        }
        Ok(())
    }

    /// `D_i -= L_i W_{i-1}` and `b_i -= L_i z_{i-1}`, with `W_{i-1} = D_{i-1}^-1 U_{i-1}`
    /// (held in `upper`) and `z_{i-1} = D_{i-1}^-1 b_{i-1}` (held in `b`).
    fn eliminate_lower(&mut self, i: usize, b: &mut [f64]) {
        let (s0, s) = (self.sizes[i - 1], self.sizes[i]);
        let (off, at) = (self.off_at[i - 1], self.diag_at[i]);
        let (prev, row) = (self.row_at[i - 1], self.row_at[i]);
        for r in 0..s {
            let l = &self.lower[off + r * s0..off + (r + 1) * s0];
            self.work[..s].fill(0.0);
            let mut rhs = 0.0;
            for (k, &lk) in l.iter().enumerate() {
                if lk == 0.0 {
                    continue;
                }
                rhs += lk * b[prev + k];
                let w = &self.upper[off + k * s..off + (k + 1) * s];
                for (acc, &wc) in self.work[..s].iter_mut().zip(w) {
                    *acc += lk * wc;
                }
            }
            b[row + r] -= rhs;
            let d = &mut self.diag[at + r * s..at + (r + 1) * s];
            for (dc, &acc) in d.iter_mut().zip(&self.work[..s]) {
                *dc -= acc;
            }
        }
    }
}

/// LU factorisation with partial pivoting of the `n` by `n` row-major matrix `a`, in place.
fn lu_factor(a: &mut [f64], n: usize, pivots: &mut [usize]) -> Result<(), ()> {
    let scale = a.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    if !(scale.is_finite() && scale > 0.0) {
        return Err(());
    }
    for k in 0..n {
        let p = (k..n)
            .max_by(|&i, &j| a[i * n + k].abs().total_cmp(&a[j * n + k].abs()))
            .unwrap_or(k);
        pivots[k] = p;
        if p != k {
            for c in 0..n {
                a.swap(k * n + c, p * n + c);
            }
        }
        let pivot = a[k * n + k];
        if pivot.abs() <= SINGULAR * scale {
            return Err(());
        }
        for r in k + 1..n {
            let f = a[r * n + k] / pivot;
            a[r * n + k] = f;
            if f != 0.0 {
                for c in k + 1..n {
                    a[r * n + c] -= f * a[k * n + c];
                }
            }
        }
    }
    Ok(())
}

/// Solves `A X = B` for the `n` by `m` row-major right-hand sides `b`, in place, with `a`
/// and `pivots` from [`lu_factor`].
fn lu_solve(a: &[f64], n: usize, pivots: &[usize], b: &mut [f64], m: usize) {
    for (k, &p) in pivots.iter().enumerate().take(n) {
        if p != k {
            for c in 0..m {
                b.swap(k * m + c, p * m + c);
            }
        }
    }
    for r in 1..n {
        for k in 0..r {
            let f = a[r * n + k];
            if f != 0.0 {
                for c in 0..m {
                    b[r * m + c] -= f * b[k * m + c];
                }
            }
        }
    }
    for r in (0..n).rev() {
        for k in r + 1..n {
            let f = a[r * n + k];
            if f != 0.0 {
                for c in 0..m {
                    b[r * m + c] -= f * b[k * m + c];
                }
            }
        }
        let d = a[r * n + r];
        for c in 0..m {
            b[r * m + c] /= d;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small deterministic generator, so the test needs no crate.
    fn noise(seed: &mut u64) -> f64 {
        *seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((*seed >> 11) as f64 / (1u64 << 53) as f64) - 0.5
    }

    #[test]
    fn solves_a_block_tridiagonal_system_as_a_dense_one_does() {
        let sizes = [2, 3, 1, 4, 2, 2];
        let n: usize = sizes.iter().sum();
        let mut seed = 7;
        let mut dense = vec![vec![0.0; n]; n];
        let mut system = BlockTridiag::default();
        system.reset(&sizes);
        for i in 0..sizes.len() {
            let at = system.row_at(i);
            for r in 0..sizes[i] {
                for c in 0..sizes[i] {
                    let v = noise(&mut seed) + if r == c { 3.0 } else { 0.0 };
                    *system.diag_mut(i, r, c) = v;
                    dense[at + r][at + c] = v;
                }
            }
            if i + 1 < sizes.len() {
                let next = system.row_at(i + 1);
                for r in 0..sizes[i] {
                    for c in 0..sizes[i + 1] {
                        let (u, l) = (noise(&mut seed), noise(&mut seed));
                        *system.upper_mut(i, r, c) = u;
                        dense[at + r][next + c] = u;
                        *system.lower_mut(i, c, r) = l;
                        dense[next + c][at + r] = l;
                    }
                }
            }
        }
        let want: Vec<f64> = (0..n).map(|_| noise(&mut seed)).collect();
        let mut b: Vec<f64> = dense
            .iter()
            .map(|row| row.iter().zip(&want).map(|(a, x)| a * x).sum())
            .collect();
        system.solve(&mut b).expect("not singular");
        for (got, want) in b.iter().zip(&want) {
            assert!((got - want).abs() < 1e-12, "{got} against {want}");
        }
    }

    #[test]
    fn a_vanishing_pivot_names_its_block() {
        let mut system = BlockTridiag::default();
        system.reset(&[1, 1]);
        *system.diag_mut(0, 0, 0) = 1.0;
        *system.upper_mut(0, 0, 0) = 1.0;
        *system.lower_mut(0, 0, 0) = 1.0;
        *system.diag_mut(1, 0, 0) = 1.0;
        assert_eq!(system.solve(&mut [1.0, 1.0]), Err(Singular { block: 1 }));
    }
}
