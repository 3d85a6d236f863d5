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
        let u_end = (q0 - q_end).max(0.0).sqrt();
        let du = u_end / panels as f64;
        let dtdu = |u: f64| 2.0 * u / rate(q0 - u * u);
        let mut nodes = Vec::with_capacity(panels + 1);
        let mut t = 0.0;
        nodes.push([0.0, 0.0, 0.0]);
        for k in 0..panels {
            let lo = du * k as f64;
            t += gauss5(lo, lo + du, dtdu);
            nodes.push([lo + du, t, dtdu(lo + du)]);
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
