//! The falling folded chain's closed form: a uniform, perfectly flexible chain of length
//! `L` and line density `lambda`, one end pinned, the other released from rest level with
//! it and beside it (separation 0), its energy conserved.
//!
//! With `x` how far the free end has fallen, the pinned arm hangs at rest, `(L + x) / 2`
//! long; the free arm, `(L - x) / 2` long, falls at the tip's speed `v`; the fold is at depth
//! `(L + x) / 2`. The potential energy released is `lambda g x (2L - x) / 4` (each arm's
//! length times its centre's depth), all of it kinetic in the free arm,
//! `lambda (L - x) v^2 / 4`:
//!
//! ```text
//! v^2 = g x (2L - x) / (L - x)
//! a_tip / g = (1 + (L / (L - x))^2) / 2             (d(v^2)/dx / 2)
//! pin force = lambda g (L + x) / 2 + lambda v^2 / 4   (the pinned arm's weight, and the
//!                                                      momentum the fold stops: the free
//!                                                      arm's momentum lambda (L-x) v / 2
//!                                                      changes at lambda g (L-x)/2 - that)
//! t(x) = int_0^x dx' / v(x'),   t(L) = 0.8472 sqrt(2 L / g)
//! ```
//!
//! The tip falls faster than g from the start (`a_tip = g` at `x = 0`, then more), and its
//! speed is unbounded at `x = L`: the whip. The experiments that found the tip faster than
//! g are cited in `docs/folded-chain.md`. Pure `f64`.

use crate::theory::trajectory::Trajectory;

/// Quadrature panels of `t(x)`: `t(L)` is good to 1e-12 relative with them.
const PANELS: usize = 400;

/// The closed form of a folded chain of length `length_m`, mass `mass_kg`, under `g`.
#[derive(Debug, Clone)]
pub struct FoldedFall {
    length_m: f64,
    lambda: f64,
    g: f64,
    /// `t(q)` with `q = sqrt(L - x)`: the table's grid, graded towards the start, takes the
    /// start from rest (`v ~ sqrt(x)`), and in `q` the end's `dt/dx ~ sqrt(L - x)` is smooth.
    table: Trajectory,
}

impl FoldedFall {
    /// The fall of a chain of `length_m` and `mass_kg` under `g_m_s2`.
    pub fn new(length_m: f64, mass_kg: f64, g_m_s2: f64) -> Self {
        let speed = |x: f64| {
            let left = length_m - x;
            if left <= 0.0 {
                f64::INFINITY
            } else {
                (g_m_s2 * x * (2.0 * length_m - x) / left).sqrt()
            }
        };
        let table = Trajectory::new(length_m.sqrt(), 0.0, PANELS, |q| {
            speed(length_m - q * q) / (2.0 * q)
        });
        Self {
            length_m,
            lambda: mass_kg / length_m,
            g: g_m_s2,
            table,
        }
    }

    /// The tip's speed after falling `x` (m/s).
    pub fn speed(&self, x: f64) -> f64 {
        let l = self.length_m;
        (self.g * x * (2.0 * l - x) / (l - x)).sqrt()
    }

    /// The tip's downward acceleration after falling `x` (m/s²).
    pub fn tip_acceleration(&self, x: f64) -> f64 {
        let r = self.length_m / (self.length_m - x);
        0.5 * self.g * (1.0 + r * r)
    }

    /// The pin's upward force on the chain after the tip has fallen `x` (N).
    pub fn pin_force(&self, x: f64) -> f64 {
        let v = self.speed(x);
        0.5 * self.lambda * self.g * (self.length_m + x) + 0.25 * self.lambda * v * v
    }

    /// The chain's downward momentum after the tip has fallen `x`: the free arm's (kg m/s).
    pub fn momentum(&self, x: f64) -> f64 {
        0.5 * self.lambda * (self.length_m - x) * self.speed(x)
    }

    /// The potential energy released when the tip has fallen `x` (J).
    pub fn released_j(&self, x: f64) -> f64 {
        0.25 * self.lambda * self.g * x * (2.0 * self.length_m - x)
    }

    /// The time at which the tip has fallen `x` (s); `None` outside `0..=L`.
    pub fn time_at(&self, x: f64) -> Option<f64> {
        if !(0.0..=self.length_m).contains(&x) {
            return None;
        }
        // The table's end is q = 0 up to rounding.
        let q = (self.length_m - x).sqrt().max(self.table.q_end());
        self.table.time_at(q)
    }

    /// The time the tip takes to fall the whole length `L` (s).
    pub fn fall_time(&self) -> f64 {
        self.time_at(self.length_m)
            .expect("the table reaches x = L")
    }
}

/// Cayley's falling chain: a uniform, perfectly flexible chain of length `L` hanging
/// straight, its lower end at a table, let go at rest. Nothing pulls the part still in the
/// air, so its top falls freely, and each element stops dead on the pile. The table then
/// holds the landed length's weight and takes the momentum that lands each second:
///
/// ```text
/// x = g t^2 / 2,  v^2 = 2 g x,  t(L) = sqrt(2 L / g)
/// table force = lambda g x + lambda v^2 = 3 lambda g x   (x < L; lambda g L after)
/// ```
///
/// (Cayley 1857; the falling chain of Hamm and Geminard, Am. J. Phys. 78, 828, 2010, whose
/// chain's top fell faster than g.)
#[derive(Debug, Clone, Copy)]
pub struct CayleyFall {
    length_m: f64,
    lambda: f64,
    g: f64,
}

impl CayleyFall {
    /// The fall of a chain of `length_m` and `mass_kg` under `g_m_s2`.
    pub fn new(length_m: f64, mass_kg: f64, g_m_s2: f64) -> Self {
        Self {
            length_m,
            lambda: mass_kg / length_m,
            g: g_m_s2,
        }
    }

    /// The top's speed after falling `x` (m/s).
    pub fn speed(&self, x: f64) -> f64 {
        (2.0 * self.g * x.max(0.0)).sqrt()
    }

    /// The table's upward force after the top has fallen `x` (N).
    pub fn table_force(&self, x: f64) -> f64 {
        if x < self.length_m {
            3.0 * self.lambda * self.g * x.max(0.0)
        } else {
            self.lambda * self.g * self.length_m
        }
    }

    /// The time at which the top has fallen `x` (s); `None` outside `0..=L`.
    pub fn time_at(&self, x: f64) -> Option<f64> {
        (0.0..=self.length_m)
            .contains(&x)
            .then(|| (2.0 * x / self.g).sqrt())
    }

    /// The time the top takes to fall the whole length `L` (s).
    pub fn fall_time(&self) -> f64 {
        (2.0 * self.length_m / self.g).sqrt()
    }
}

/// The closed form a chain's run is held against: the folded chain's, or Cayley's.
#[derive(Debug, Clone)]
pub enum ChainFall {
    /// The folded chain, its pin holding one end ([`FoldedFall`]).
    Folded(FoldedFall),
    /// Cayley's hanging chain falling onto a table ([`CayleyFall`]).
    Cayley(CayleyFall),
}

impl ChainFall {
    /// The free end's speed after falling `x` (m/s).
    pub fn speed(&self, x: f64) -> f64 {
        match self {
            Self::Folded(f) => f.speed(x),
            Self::Cayley(f) => f.speed(x),
        }
    }

    /// The time at which the free end has fallen `x` (s); `None` outside `0..=L`.
    pub fn time_at(&self, x: f64) -> Option<f64> {
        match self {
            Self::Folded(f) => f.time_at(x),
            Self::Cayley(f) => f.time_at(x),
        }
    }

    /// The time the free end takes to fall the whole length (s).
    pub fn fall_time(&self) -> f64 {
        match self {
            Self::Folded(f) => f.fall_time(),
            Self::Cayley(f) => f.fall_time(),
        }
    }

    /// The pin's upward force after the free end has fallen `x` (N; none without a pin).
    pub fn pin_force(&self, x: f64) -> f64 {
        match self {
            Self::Folded(f) => f.pin_force(x),
            Self::Cayley(_) => 0.0,
        }
    }

    /// The floor's upward force after the free end has fallen `x` (N), where the closed
    /// form has one: Cayley's table.
    pub fn floor_force(&self, x: f64) -> Option<f64> {
        match self {
            Self::Folded(_) => None,
            Self::Cayley(f) => Some(f.table_force(x)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cayleys_table_holds_the_pile_and_stops_what_lands() {
        let (l, m, g) = (0.5, 0.2, 9.81);
        let fall = CayleyFall::new(l, m, g);
        let lambda = m / l;
        for x in [0.05, 0.2, 0.45] {
            let t = fall.time_at(x).unwrap();
            assert!((0.5 * g * t * t / x - 1.0).abs() < 1e-12);
            // The chain's momentum is the airborne part's, lambda (L - x) v downward; its
            // rate is the weight less the table's force.
            let p = |x: f64| lambda * (l - x) * fall.speed(x);
            let h = 1e-7;
            let dp_dt = (p(x + h) - p(x - h)) / (2.0 * h) * fall.speed(x);
            assert!(
                (m * g - fall.table_force(x) - dp_dt).abs() < 1e-6 * m * g,
                "x = {x}"
            );
        }
        assert!((fall.table_force(l) - m * g).abs() < 1e-15);
        assert!(fall.time_at(1.1 * l).is_none());
    }

    #[test]
    fn fall_time_is_0_847_of_free_fall() {
        for (l, g) in [(1.0, 9.81), (0.3, 1.0), (5.0, 20.0)] {
            let fall = FoldedFall::new(l, 0.1, g);
            let ratio = fall.fall_time() / (2.0 * l / g).sqrt();
            // int_0^1 sqrt((1 - s) / (s (2 - s))) ds / sqrt(2), by an independent quadrature
            // (mpmath, 30 digits): 0.847213084793979...
            assert!((ratio - 0.847_213_084_793_98).abs() < 1e-9, "{ratio}");
        }
    }

    #[test]
    fn speed_and_acceleration_agree() {
        let fall = FoldedFall::new(1.0, 0.1, 9.81);
        for x in [0.01, 0.25, 0.5, 0.75, 0.9] {
            let h = 1e-6;
            let dv2 = (fall.speed(x + h).powi(2) - fall.speed(x - h).powi(2)) / (2.0 * h);
            assert!((0.5 * dv2 / fall.tip_acceleration(x) - 1.0).abs() < 1e-8);
            // dt/dx = 1/v from the table.
            let dt = (fall.time_at(x + h).unwrap() - fall.time_at(x - h).unwrap()) / (2.0 * h);
            assert!((dt * fall.speed(x) - 1.0).abs() < 1e-6, "x = {x}");
        }
        assert!((fall.tip_acceleration(0.0) - 9.81).abs() < 1e-12);
    }

    #[test]
    fn energy_and_momentum_balance() {
        let (l, m, g) = (1.0, 0.1, 9.81);
        let fall = FoldedFall::new(l, m, g);
        let lambda = m / l;
        for x in [0.1, 0.5, 0.8] {
            let v = fall.speed(x);
            // The released energy is the free arm's kinetic energy.
            let kinetic = 0.25 * lambda * (l - x) * v * v;
            assert!((kinetic / fall.released_j(x) - 1.0).abs() < 1e-12);
            // Momentum: the chain's is the free arm's, lambda (L - x) v / 2, downward; its
            // rate (with dx/dt = v) is the weight less the pin's force.
            let h = 1e-6;
            let dp_dt = (fall.momentum(x + h) - fall.momentum(x - h)) / (2.0 * h) * v;
            assert!(
                (m * g - fall.pin_force(x) - dp_dt).abs() < 1e-6 * m * g,
                "x = {x}"
            );
        }
    }
}
