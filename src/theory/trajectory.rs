//! One-degree-of-freedom quadrature shared by the references: a motion with a conserved (or
//! closed-form) first integral, tabulated as `t(q)` by Gauss quadrature of `dt = dq / |q'|`
//! on a grid graded towards the start (`q = q0 - u^2`), which stays accurate up to the
//! singular end, and read back with cubic Hermite interpolation in `u`. It knows no
//! physics: the rate `|q'|(q)` comes from the model that uses it.

use crate::spiral::gauss5;

/// A one-degree-of-freedom motion tabulated from its start to its end.
///
/// `q` falls monotonically from `q0`; the grid is uniform in `u = sqrt(q0 - q)`, so a start
/// from rest (`|q'| ~ sqrt(q0 - q)`) is integrated without loss of order.
#[derive(Debug, Clone)]
pub(crate) struct Trajectory {
    q0: f64,
    /// `(u, t, dt/du)` at each node.
    nodes: Vec<[f64; 3]>,
}

impl Trajectory {
    pub(crate) fn new(q0: f64, q_end: f64, panels: usize, rate: impl Fn(f64) -> f64) -> Self {
        let (du, dtdu) = Self::integrand(q0, q_end, panels, &rate);
        let parts = (0..panels).map(|k| Self::panel(k, du, &dtdu));
        Self::from_panels(q0, du, parts)
    }

    /// [`Self::new`] with the panels evaluated in parallel (they are independent), the times
    /// summed in order: the same bits, in a fraction of the time on more than one core. The
    /// threads are its own, one per core in contiguous blocks of panels, not a rayon pool's:
    /// a sweep's runs go on a pool of `--jobs` threads, where a nested parallel loop would
    /// run on the one thread of `--jobs 1`.
    pub(crate) fn new_parallel(
        q0: f64,
        q_end: f64,
        panels: usize,
        rate: impl Fn(f64) -> f64 + Sync,
    ) -> Self {
        let (du, dtdu) = Self::integrand(q0, q_end, panels, &rate);
        let threads = std::thread::available_parallelism().map_or(1, usize::from);
        let block = panels.div_ceil(threads.max(1)).max(1);
        let dtdu = &dtdu;
        let parts: Vec<(f64, f64)> = std::thread::scope(|scope| {
            let workers: Vec<_> = (0..panels)
                .step_by(block)
                .map(|start| {
                    scope.spawn(move || {
                        (start..(start + block).min(panels))
                            .map(|k| Self::panel(k, du, dtdu))
                            .collect::<Vec<_>>()
                    })
                })
                .collect();
            workers
                .into_iter()
                .flat_map(|w| w.join().expect("a trajectory panel panicked"))
                .collect()
        });
        Self::from_panels(q0, du, parts)
    }

    /// The panels' width in `u = sqrt(q0 - q)` and `dt/du`.
    fn integrand<'r>(
        q0: f64,
        q_end: f64,
        panels: usize,
        rate: &'r (impl Fn(f64) -> f64 + ?Sized),
    ) -> (f64, impl Fn(f64) -> f64 + 'r) {
        let u_end = (q0 - q_end).max(0.0).sqrt();
        (u_end / panels as f64, move |u: f64| {
            2.0 * u / rate(q0 - u * u)
        })
    }

    /// Panel `k`'s time and the slope `dt/du` at its end.
    fn panel(k: usize, du: f64, dtdu: &impl Fn(f64) -> f64) -> (f64, f64) {
        let lo = du * k as f64;
        (gauss5(lo, lo + du, dtdu), dtdu(lo + du))
    }

    /// The table from the panels' times and end slopes, the times summed in order.
    fn from_panels(q0: f64, du: f64, parts: impl IntoIterator<Item = (f64, f64)>) -> Self {
        let mut nodes = vec![[0.0, 0.0, 0.0]];
        let mut t = 0.0;
        for (k, (dt, slope)) in parts.into_iter().enumerate() {
            t += dt;
            nodes.push([du * k as f64 + du, t, slope]);
        }
        Self { q0, nodes }
    }

    /// A table with no nodes yet, for a model that needs itself to compute its rate.
    pub(crate) fn empty(q0: f64) -> Self {
        Self { q0, nodes: vec![] }
    }

    /// The last tabulated `q`.
    pub(crate) fn q_end(&self) -> f64 {
        let u = self.nodes.last().map_or(0.0, |n| n[0]);
        self.q0 - u * u
    }

    /// The time at the last tabulated `q` (s).
    fn duration(&self) -> f64 {
        self.nodes.last().map_or(0.0, |n| n[1])
    }

    /// Time at which `q` is reached, `None` beyond the tabulated end.
    pub(crate) fn time_at(&self, q: f64) -> Option<f64> {
        if q > self.q0 || q < self.q_end() {
            return None;
        }
        let u = (self.q0 - q).sqrt();
        let k = self
            .nodes
            .partition_point(|n| n[0] <= u)
            .clamp(1, self.nodes.len() - 1);
        let (a, b) = (self.nodes[k - 1], self.nodes[k]);
        Some(hermite(a[0], b[0], a[1], b[1], a[2], b[2], u))
    }

    /// `q` at time `t`, `None` beyond the tabulated end.
    pub(crate) fn q_at(&self, t: f64) -> Option<f64> {
        if t < 0.0 || t > self.duration() {
            return None;
        }
        let k = self
            .nodes
            .partition_point(|n| n[1] <= t)
            .clamp(1, self.nodes.len() - 1);
        let (a, b) = (self.nodes[k - 1], self.nodes[k]);
        // Invert the monotone Hermite piece by bisection (robust, ~50 halvings).
        let (mut lo, mut hi) = (a[0], b[0]);
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if hermite(a[0], b[0], a[1], b[1], a[2], b[2], mid) < t {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let u = 0.5 * (lo + hi);
        Some(self.q0 - u * u)
    }
}

/// Cubic Hermite interpolation of `y(x)` between `(x0, y0, d0)` and `(x1, y1, d1)`.
fn hermite(x0: f64, x1: f64, y0: f64, y1: f64, d0: f64, d1: f64, x: f64) -> f64 {
    let h = x1 - x0;
    let s = (x - x0) / h;
    let s2 = s * s;
    let s3 = s2 * s;
    (2.0 * s3 - 3.0 * s2 + 1.0) * y0
        + (s3 - 2.0 * s2 + s) * h * d0
        + (-2.0 * s3 + 3.0 * s2) * y1
        + (s3 - s2) * h * d1
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_parallel_table_is_the_serial_one_bit_for_bit() {
        // A coil-like rate, zero at the start (from rest) and growing.
        let rate = |q: f64| (1.0 - q).sqrt() * (2.0 - q).powf(1.5);
        for panels in [1, 7, 6000, 6001] {
            let serial = Trajectory::new(1.0, 0.01, panels, rate);
            let parallel = Trajectory::new_parallel(1.0, 0.01, panels, rate);
            let bits = |t: &Trajectory| {
                t.nodes
                    .iter()
                    .flat_map(|n| n.map(f64::to_bits))
                    .collect::<Vec<_>>()
            };
            assert_eq!(bits(&serial), bits(&parallel), "{panels} panels");
        }
    }
}
