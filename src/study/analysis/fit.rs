//! The fits a sweep's analysis rests on: least-squares power laws in log-log
//! ([`fit_power`]), the step size a setting stands for ([`step_size`]) and the Pareto
//! front ([`pareto_front`]). Pure `f64`: it knows no sweep table and writes no text.

/// A least-squares fit of `log10 y = order * log10 x + log10_c`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PowerFit {
    /// The exponent: the convergence order when `x` is a step size and `y` an error.
    pub order: f64,
    /// The intercept, `log10` of the constant.
    pub log10_c: f64,
    /// Standard error of `order`.
    pub order_se: f64,
    /// Coefficient of determination of the log-log line (1 = a perfect power law).
    pub r2: f64,
    /// Points used.
    pub n: usize,
}

impl PowerFit {
    /// The fitted `y` at `x`.
    pub fn eval(&self, x: f64) -> f64 {
        10f64.powf(self.log10_c + self.order * x.log10())
    }
}

/// The fewest points a fit is made from: a line through two points always fits them
/// (R² = 1), so it says nothing of a power law.
pub const MIN_FIT_POINTS: usize = 3;

/// Fits `y = C x^order` by least squares on `(log10 x, log10 y)`, using the points where
/// both are finite and positive; `None` if fewer than `MIN_FIT_POINTS` (3) such points or all
/// `x` are equal.
pub fn fit_power(x: &[f64], y: &[f64]) -> Option<PowerFit> {
    let pts: Vec<(f64, f64)> = x
        .iter()
        .zip(y)
        .filter(|(a, b)| a.is_finite() && b.is_finite() && **a > 0.0 && **b > 0.0)
        .map(|(a, b)| (a.log10(), b.log10()))
        .collect();
    let n = pts.len();
    if n < MIN_FIT_POINTS {
        return None;
    }
    let nf = n as f64;
    let mx = pts.iter().map(|p| p.0).sum::<f64>() / nf;
    let my = pts.iter().map(|p| p.1).sum::<f64>() / nf;
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let syy: f64 = pts.iter().map(|p| (p.1 - my).powi(2)).sum();
    // All x equal (to rounding): no slope to fit.
    if sxx <= 1e-12 * nf {
        return None;
    }
    let order = sxy / sxx;
    let log10_c = my - order * mx;
    let ss_res: f64 = pts
        .iter()
        .map(|p| (p.1 - (log10_c + order * p.0)).powi(2))
        .sum();
    let r2 = if syy > 0.0 { 1.0 - ss_res / syy } else { 1.0 };
    let order_se = (ss_res / (nf - 2.0) / sxx).sqrt();
    Some(PowerFit {
        order,
        order_se,
        log10_c,
        r2,
        n,
    })
}

/// Whether a varied key is a resolution of the model (its discretisation or its solver),
/// which a result converges in and whose step size [`step_size`] stands for; any other key
/// (the tape, the floor, gravity, the push, the stop) is physical: a result depends on it,
/// and it is drawn on its own axis with its own values, never fitted as a step.
pub fn is_resolution(key: &str) -> bool {
    key.starts_with("discretisation.") || key.starts_with("solver.")
}

/// The step size a setting stands for, so that a convergence order is positive when the
/// error falls as the setting is refined: a key naming a size in its unit (`_s`, `_m`,
/// `_rad`, e.g. `solver.max_dt_s`, `solver.bang_step_rad`) or a tolerance
/// (`solver.bang_tolerance`, finer as it falls) is the step itself; any other (a count or
/// rate, e.g. `discretisation.links_per_turn`, `solver.steps_per_link`) gives `1 / value`.
pub fn step_size(key: &str, value: f64) -> f64 {
    if key.ends_with("_s")
        || key.ends_with("_m")
        || key.ends_with("_rad")
        || key.ends_with("_tolerance")
    {
        value
    } else {
        1.0 / value
    }
}

/// The indices of the Pareto front: points no other point beats in both cost and error
/// (lower is better for both), sorted by cost. Non-finite points are ignored.
pub fn pareto_front(cost: &[f64], err: &[f64]) -> Vec<usize> {
    let mut idx: Vec<usize> = (0..cost.len())
        .filter(|&i| cost[i].is_finite() && err[i].is_finite())
        .collect();
    idx.sort_by(|&a, &b| cost[a].total_cmp(&cost[b]).then(err[a].total_cmp(&err[b])));
    let mut front = Vec::new();
    let mut best = f64::INFINITY;
    for i in idx {
        if err[i] < best {
            best = err[i];
            front.push(i);
        }
    }
    front
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn fit_recovers_a_power_law() {
        // Synthetic convergence data: err = 0.3 h^1.7, exact, and with +-5% noise.
        let h: Vec<f64> = [1.0 / 8.0, 1.0 / 16.0, 1.0 / 32.0, 1.0 / 64.0].to_vec();
        let e: Vec<f64> = h.iter().map(|h| 0.3 * h.powf(1.7)).collect();
        let f = fit_power(&h, &e).unwrap();
        assert_relative_eq!(f.order, 1.7, epsilon = 1e-12);
        assert_relative_eq!(f.eval(1.0), 0.3, epsilon = 1e-12);
        assert_relative_eq!(f.r2, 1.0, epsilon = 1e-12);
        assert_eq!(f.n, 4);
        let noisy: Vec<f64> = e
            .iter()
            .zip([1.05, 0.95, 1.05, 0.95])
            .map(|(e, k)| e * k)
            .collect();
        let f = fit_power(&h, &noisy).unwrap();
        assert!(
            (f.order - 1.7).abs() < 0.1,
            "order {:.3}, expected ~1.7",
            f.order
        );
        assert!(f.r2 < 1.0 && f.r2 > 0.99, "R² {}", f.r2);
        assert!(
            f.order_se > 0.0 && f.order_se < 0.1,
            "standard error {}",
            f.order_se
        );
    }

    #[test]
    fn fit_skips_unusable_points() {
        let h = [0.1, 0.05, f64::NAN, 0.01, 0.02];
        let e = [1e-2, 2.5e-3, 1.0, 0.0, 4e-4];
        let f = fit_power(&h, &e).unwrap();
        assert_eq!(f.n, 3);
        assert_relative_eq!(f.order, 2.0, epsilon = 1e-9);
        assert!(fit_power(&[0.1, 0.1], &[1.0, 2.0]).is_none());
        // Equal up to rounding (704 links computed two ways) is still equal.
        assert!(fit_power(&[704.0, 704.0 * (1.0 + 1e-15), 704.0], &[1.0, 2.0, 3.0]).is_none());
        assert!(fit_power(&[0.1], &[1.0]).is_none());
    }

    #[test]
    fn step_size_follows_the_unit() {
        assert!((step_size("solver.bang_step_rad", 0.15) - 0.15).abs() < 1e-15);
        assert!((step_size("solver.bang_tolerance", 1e-3) - 1e-3).abs() < 1e-18);
        assert_relative_eq!(step_size("solver.max_dt_s", 1e-3), 1e-3);
        assert_relative_eq!(step_size("discretisation.links_per_turn", 32.0), 1.0 / 32.0);
        assert_relative_eq!(step_size("solver.steps_per_link", 4.0), 0.25);
    }

    #[test]
    fn pareto_front_keeps_the_undominated() {
        let cost = [1.0, 2.0, 3.0, 0.5, 2.5, f64::NAN];
        let err = [0.1, 0.2, 0.01, 0.5, 0.05, 0.0];
        assert_eq!(pareto_front(&cost, &err), vec![3, 0, 4, 2]);
    }
}
