//! A block-tridiagonal linear system solved exactly by block LU (block Thomas), in time
//! linear in its number of blocks: each diagonal block's Schur complement a small dense
//! matrix inverted with partial pivoting, no iteration count. It knows nothing of chains or
//! contacts.
//!
//! ```text
//! | D_0 U_0             | | x_0 |   | b_0 |
//! | L_1 D_1 U_1         | | x_1 |   | b_1 |
//! |     L_2 D_2 U_2     | | x_2 | = | b_2 |
//! |         ...         | | ... |   | ... |
//! ```
//!
//! Factor: `D_i <- D_i - L_i D_{i-1}^-1 U_{i-1}`; forward: `z_i = D_i^-1 (b_i - L_i
//! z_{i-1})`; back: `x_i = z_i - D_i^-1 U_i x_{i+1}`. One factorisation serves many
//! right-hand sides.

/// A pivot smaller than this fraction of its block's largest entry means a singular system.
const SINGULAR: f64 = 1e-13;

/// The system's blocks, reused from solve to solve (nothing is allocated once grown).
#[derive(Debug, Default)]
pub(in crate::model) struct BlockTridiag {
    sizes: Vec<usize>,
    /// First unknown of each block.
    row_at: Vec<usize>,
    diag_at: Vec<usize>,
    /// Offset of `U_i` (block i by block i + 1), and of `L_{i+1}` (block i + 1 by block i).
    off_at: Vec<usize>,
    diag: Vec<f64>,
    upper: Vec<f64>,
    lower: Vec<f64>,
    /// Room for a block's inverse or product.
    work: Vec<f64>,
}

/// The system could not be solved: block `block`'s pivot vanished.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(in crate::model) struct Singular {
    pub(in crate::model) block: usize,
}

impl BlockTridiag {
    /// Sets the block sizes and zeroes every block.
    pub(in crate::model) fn reset(&mut self, sizes: &[usize]) {
        if self.sizes == sizes {
            self.diag.fill(0.0);
            self.upper.fill(0.0);
            self.lower.fill(0.0);
            return;
        }
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
    }

    /// Block `i`'s first unknown.
    pub(in crate::model) fn row_at(&self, i: usize) -> usize {
        self.row_at[i]
    }

    /// Block `i`'s size.
    pub(in crate::model) fn size(&self, i: usize) -> usize {
        self.sizes[i]
    }

    /// Block `i`'s diagonal block, and `U_i` and `L_{i+1}` (empty for the last block), each
    /// row-major.
    pub(in crate::model) fn blocks_mut(&mut self, i: usize) -> [&mut [f64]; 3] {
        let s = self.sizes[i];
        let s1 = self.sizes.get(i + 1).copied().unwrap_or(0);
        let (at, off) = (self.diag_at[i], self.off_at[i]);
        [
            &mut self.diag[at..at + s * s],
            &mut self.upper[off..off + s * s1],
            &mut self.lower[off..off + s * s1],
        ]
    }

    /// The entry at `(r, c)` within diagonal block `i` (the tests fill a system entry by
    /// entry; the exact chain, block by block with [`Self::blocks_mut`]).
    #[cfg(test)]
    fn diag_mut(&mut self, i: usize, r: usize, c: usize) -> &mut f64 {
        let s = self.sizes[i];
        &mut self.diag[self.diag_at[i] + r * s + c]
    }

    /// The entry at `(r, c)` of `U_i`: row `r` of block `i`, column `c` of block `i + 1`.
    #[cfg(test)]
    fn upper_mut(&mut self, i: usize, r: usize, c: usize) -> &mut f64 {
        let s = self.sizes[i + 1];
        &mut self.upper[self.off_at[i] + r * s + c]
    }

    /// The entry at `(r, c)` of `L_{i+1}`: row `r` of block `i + 1`, column `c` of block `i`.
    #[cfg(test)]
    fn lower_mut(&mut self, i: usize, r: usize, c: usize) -> &mut f64 {
        let s = self.sizes[i];
        &mut self.lower[self.off_at[i] + r * s + c]
    }

    /// Factorises the system in place: each diagonal block becomes the inverse of its Schur
    /// complement, each `U_i` becomes `D_i^-1 U_i`. Fill the blocks again (after `reset`)
    /// before the next factorisation.
    pub(in crate::model) fn factor(&mut self) -> Result<(), Singular> {
        let n = self.sizes.len();
        for i in 0..n {
            let (s, at) = (self.sizes[i], self.diag_at[i]);
            let pair = |j: usize| self.sizes.get(j) == Some(&2);
            // A joint's block between two joints' (most of a chain's): in 2 by 2 arrays.
            if i > 0 && pair(i - 1) && pair(i) && (i + 1 == n || pair(i + 1)) {
                self.factor_pair(i).map_err(|()| Singular { block: i })?;
                continue;
            }
            if i > 0 {
                self.eliminate_lower(i);
            }
            invert(&mut self.diag[at..at + s * s], s, &mut self.work)
                .map_err(|()| Singular { block: i })?;
            if i + 1 < n {
                let (s1, off) = (self.sizes[i + 1], self.off_at[i]);
                let inverse = &self.diag[at..at + s * s];
                let upper = &mut self.upper[off..off + s * s1];
                multiply_in_place(inverse, s, upper, s1, &mut self.work);
            }
        }
        Ok(())
    }

    /// [`Self::factor`]'s work on block `i`, of size 2 as are its neighbours: the same
    /// operations in the same order as the general path's, on arrays.
    fn factor_pair(&mut self, i: usize) -> Result<(), ()> {
        let (off, at) = (self.off_at[i - 1], self.diag_at[i]);
        let l = take4(&self.lower[off..]);
        let w = take4(&self.upper[off..]);
        let mut d = take4(&self.diag[at..]);
        for r in 0..2 {
            for k in 0..2 {
                let lk = l[2 * r + k];
                if lk != 0.0 {
                    d[2 * r] -= lk * w[2 * k];
                    d[2 * r + 1] -= lk * w[2 * k + 1];
                }
            }
        }
        let inverse = invert_pair(d)?;
        self.diag[at..at + 4].copy_from_slice(&inverse);
        if i + 1 < self.sizes.len() {
            let off = self.off_at[i];
            let u = take4(&self.upper[off..]);
            let mut product = [0.0; 4];
            for r in 0..2 {
                for k in 0..2 {
                    let f = inverse[2 * r + k];
                    if f != 0.0 {
                        product[2 * r] += f * u[2 * k];
                        product[2 * r + 1] += f * u[2 * k + 1];
                    }
                }
            }
            self.upper[off..off + 4].copy_from_slice(&product);
        }
        Ok(())
    }

    /// Solves the factorised system for `b`, which becomes the solution.
    pub(in crate::model) fn solve(&self, b: &mut [f64]) {
        let n = self.sizes.len();
        let mut z = [0.0; MAX_INLINE];
        for i in 0..n {
            let (s, at, row) = (self.sizes[i], self.diag_at[i], self.row_at[i]);
            if s == 2 && i > 0 && self.sizes[i - 1] == 2 {
                // Between two joints' blocks: the same sums, on arrays.
                let (off, prev) = (self.off_at[i - 1], self.row_at[i - 1]);
                let l = take4(&self.lower[off..]);
                let x = [b[prev], b[prev + 1]];
                let y = [
                    b[row] - (l[0] * x[0] + l[1] * x[1]),
                    b[row + 1] - (l[2] * x[0] + l[3] * x[1]),
                ];
                let d = take4(&self.diag[at..]);
                b[row] = d[0] * y[0] + d[1] * y[1];
                b[row + 1] = d[2] * y[0] + d[3] * y[1];
                continue;
            }
            if i > 0 {
                let (s0, off, prev) = (self.sizes[i - 1], self.off_at[i - 1], self.row_at[i - 1]);
                for r in 0..s {
                    let l = &self.lower[off + r * s0..off + (r + 1) * s0];
                    let dot: f64 = l.iter().zip(&b[prev..prev + s0]).map(|(a, x)| a * x).sum();
                    b[row + r] -= dot;
                }
            }
            let inverse = &self.diag[at..at + s * s];
            if s <= MAX_INLINE {
                z[..s].copy_from_slice(&b[row..row + s]);
                for r in 0..s {
                    b[row + r] = inverse[r * s..(r + 1) * s]
                        .iter()
                        .zip(&z[..s])
                        .map(|(a, x)| a * x)
                        .sum();
                }
            } else {
                let rhs = b[row..row + s].to_vec();
                for r in 0..s {
                    b[row + r] = inverse[r * s..(r + 1) * s]
                        .iter()
                        .zip(&rhs)
                        .map(|(a, x)| a * x)
                        .sum();
                }
            }
        }
        for i in (0..n.saturating_sub(1)).rev() {
            let (s, s1, off) = (self.sizes[i], self.sizes[i + 1], self.off_at[i]);
            let (row, next) = (self.row_at[i], self.row_at[i + 1]);
            if s == 2 && s1 == 2 {
                let w = take4(&self.upper[off..]);
                let x = [b[next], b[next + 1]];
                b[row] -= w[0] * x[0] + w[1] * x[1];
                b[row + 1] -= w[2] * x[0] + w[3] * x[1];
                continue;
            }
            for r in 0..s {
                let w = &self.upper[off + r * s1..off + (r + 1) * s1];
                let dot: f64 = w.iter().zip(&b[next..next + s1]).map(|(a, x)| a * x).sum();
                b[row + r] -= dot;
            }
        }
    }

    /// `D_i -= L_i W_{i-1}`, with `W_{i-1} = D_{i-1}^-1 U_{i-1}` (held in `upper`).
    fn eliminate_lower(&mut self, i: usize) {
        let (s0, s) = (self.sizes[i - 1], self.sizes[i]);
        let (off, at) = (self.off_at[i - 1], self.diag_at[i]);
        for r in 0..s {
            let l = &self.lower[off + r * s0..off + (r + 1) * s0];
            let d = &mut self.diag[at + r * s..at + (r + 1) * s];
            for (k, &lk) in l.iter().enumerate() {
                if lk == 0.0 {
                    continue;
                }
                let w = &self.upper[off + k * s..off + (k + 1) * s];
                for (dc, &wc) in d.iter_mut().zip(w) {
                    *dc -= lk * wc;
                }
            }
        }
    }
}

/// Blocks up to this size are solved without allocating.
const MAX_INLINE: usize = 16;

/// Inverts the `n` by `n` row-major matrix `a` in place by Gauss-Jordan elimination with
/// partial pivoting (a 2 by 2 block, the joints' alone, in closed form); `work` holds at
/// least `2 n` entries. Fails if a pivot is below [`SINGULAR`] of the largest entry.
fn invert(a: &mut [f64], n: usize, work: &mut Vec<f64>) -> Result<(), ()> {
    let scale = a.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    if !(scale.is_finite() && scale > 0.0) {
        return Err(());
    }
    if n == 1 {
        if a[0].abs() <= SINGULAR * scale {
            return Err(());
        }
        a[0] = 1.0 / a[0];
        return Ok(());
    }
    if n == 2 {
        let inverse = invert_pair(take4(a))?;
        a.copy_from_slice(&inverse);
        return Ok(());
    }
    // Gauss-Jordan on [a | I], the right half kept in `work` row by row.
    work.clear();
    work.resize(n * n, 0.0);
    for k in 0..n {
        work[k * n + k] = 1.0;
    }
    for col in 0..n {
        let p = (col..n)
            .max_by(|&i, &j| a[i * n + col].abs().total_cmp(&a[j * n + col].abs()))
            .unwrap_or(col);
        if p != col {
            for c in 0..n {
                a.swap(col * n + c, p * n + c);
                work.swap(col * n + c, p * n + c);
            }
        }
        let d = a[col * n + col];
        if d.abs() <= SINGULAR * scale {
            return Err(());
        }
        for c in 0..n {
            a[col * n + c] /= d;
            work[col * n + c] /= d;
        }
        for r in 0..n {
            let f = a[r * n + col];
            if r == col || f == 0.0 {
                continue;
            }
            for c in 0..n {
                a[r * n + c] -= f * a[col * n + c];
                work[r * n + c] -= f * work[col * n + c];
            }
        }
    }
    a.copy_from_slice(&work[..n * n]);
    Ok(())
}

/// The first four entries of `a`.
fn take4(a: &[f64]) -> [f64; 4] {
    [a[0], a[1], a[2], a[3]]
}

/// The inverse of the 2 by 2 row-major matrix `a`, in closed form; fails as [`invert`]
/// does.
fn invert_pair(a: [f64; 4]) -> Result<[f64; 4], ()> {
    let scale = a.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    if !(scale.is_finite() && scale > 0.0) {
        return Err(());
    }
    let det = a[0] * a[3] - a[1] * a[2];
    let pivot = a[0].abs().max(a[2].abs());
    if pivot <= SINGULAR * scale || det.abs() <= SINGULAR * scale * pivot {
        return Err(());
    }
    let [p, q, r, t] = a;
    Ok([t / det, -q / det, -r / det, p / det])
}

/// `b <- a b` for the `n` by `n` matrix `a` and the `n` by `m` matrix `b`, row-major.
fn multiply_in_place(a: &[f64], n: usize, b: &mut [f64], m: usize, work: &mut Vec<f64>) {
    work.clear();
    work.resize(n * m, 0.0);
    for r in 0..n {
        for k in 0..n {
            let f = a[r * n + k];
            if f == 0.0 {
                continue;
            }
            for c in 0..m {
                work[r * m + c] += f * b[k * m + c];
            }
        }
    }
    b.copy_from_slice(&work[..n * m]);
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
        // Mixed sizes, and a pinned chain's (its first block the pin's and a joint's, then
        // joints' pairs), which takes the 2 by 2 path.
        solves_as_dense(&[2, 3, 1, 4, 2, 2], 7);
        solves_as_dense(&[4, 2, 2, 2, 2, 3, 2, 2, 2], 11);
        solves_as_dense(&[2; 12], 13);
    }

    fn solves_as_dense(sizes: &[usize], mut seed: u64) {
        let n: usize = sizes.iter().sum();
        let mut dense = vec![vec![0.0; n]; n];
        let mut system = BlockTridiag::default();
        system.reset(sizes);
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
        system.factor().expect("not singular");
        system.solve(&mut b);
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
        assert_eq!(system.factor(), Err(Singular { block: 1 }));
    }
}
