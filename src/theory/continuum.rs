//! The paper's continuum references for the horizontal uncoiling: the energy equation
//! eq. (7) with its corrected energy integral (ERRATA A1-A3), its closed form from rest,
//! and the force/torque equation eq. (17) with its closed form (ERRATA C2); the paper's
//! floor forces N, eq. (9) (ERRATA A4), and F, eq. (11) (ERRATA A6), on the eq. (7) disc.
//! Also the [`Params`] and [`RefState`] every reference shares. Pure `f64`, no engine
//! types; this module neither simulates contact nor models the real spiral (that is the
//! [`exact`](super::exact) module).

use std::f64::consts::PI;

use serde::Serialize;

use super::trajectory::Trajectory;

/// Physical inputs shared by all references.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Params {
    /// R: outer radius of the coil (m).
    pub outer_radius_m: f64,
    /// b: tape thickness (m).
    pub thickness_m: f64,
    /// M: tape mass (kg).
    pub mass_kg: f64,
    /// Inner radius of the winding (m).
    pub core_radius_m: f64,
    /// g (m/s^2).
    pub g_m_s2: f64,
    /// Initial speed of the contact line (m/s).
    pub push_speed_m_s: f64,
}

/// The state of a reference at one instant.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct RefState {
    /// Time since the push (s).
    pub t_s: f64,
    /// Mass on the floor over the total mass.
    pub laid_fraction: f64,
    /// Continuum-equivalent coil radius `R sqrt(1 - laid_fraction)` (m).
    pub r_m: f64,
    /// Position of the contact line, i.e. the laid length (m).
    pub x_m: f64,
    /// Speed of the contact line (m/s).
    pub xdot_m_s: f64,
    /// Clockwise spin of the coil (rad/s), positive when rolling towards +x.
    pub omega_rad_s: f64,
    /// Kinetic energy (J).
    pub kinetic_j: f64,
    /// Potential energy (J).
    pub potential_j: f64,
}

/// The paper's continuum model of sec. 2.1: a uniform disc of radius `r` and mass
/// `M r^2 / R^2` rolling without slip, energy conserved, laid tape weightless.
///
/// ```text
/// (6 pi^2 r^2 + b^2) r r'' + (12 pi^2 r^2 + b^2) r'^2 + 3 b^2 g r = 0          (7)
/// E = M r^2 r'^2 (6 pi^2 r^2 + b^2) / (2 b^2 R^2) + M g r^3 / R^2              (5), ERRATA A1
/// r'^2 = r0'^2 R^2 (6 pi^2 R^2 + b^2) / (r^2 (6 pi^2 r^2 + b^2))
///        + 2 g b^2 R^3 (1 - r^3/R^3) / (6 pi^2 r^4 + b^2 r^2)                   (6), ERRATA A2
/// x' = -2 pi r r' / b,  omega = x' / r                                          (1), (2)
/// ```
/// The printed (5) has a spurious factor `r0^2` and the printed (6) drops the push's growth
/// with the shrinking moment of inertia (ERRATA A1, A2, A3); both are corrected here.
#[derive(Debug, Clone)]
pub struct Continuum {
    p: Params,
    energy_j: f64,
    traj: Trajectory,
}

impl Continuum {
    /// Tabulates eq. (7) from `r = R` down to `r_end_m` (the cutoff event before the singular end).
    pub fn new(p: Params, r_end_m: f64) -> Self {
        let (big_r, b, m) = (p.outer_radius_m, p.thickness_m, p.mass_kg);
        let rdot0 = b * p.push_speed_m_s / (2.0 * PI * big_r);
        let energy_j = Self::kinetic(&p, big_r, rdot0) + m * p.g_m_s2 * big_r;
        let mut c = Self {
            p,
            energy_j,
            traj: Trajectory::empty(big_r),
        };
        c.traj = Trajectory::new(big_r, r_end_m, 4000, |r| c.rdot(r));
        c
    }

    /// Kinetic energy of eq. (3): `M r^2 r'^2 (6 pi^2 r^2 + b^2) / (2 b^2 R^2)` (J).
    fn kinetic(p: &Params, r: f64, rdot: f64) -> f64 {
        let (big_r, b) = (p.outer_radius_m, p.thickness_m);
        p.mass_kg * r * r * rdot * rdot * (6.0 * PI * PI * r * r + b * b)
            / (2.0 * b * b * big_r * big_r)
    }

    /// `|r'|` from the energy integral (eq. 6 corrected, ERRATA A2) (m/s).
    pub fn rdot(&self, r: f64) -> f64 {
        let (big_r, b, m, g) = (
            self.p.outer_radius_m,
            self.p.thickness_m,
            self.p.mass_kg,
            self.p.g_m_s2,
        );
        let kin = (self.energy_j - m * g * r.powi(3) / (big_r * big_r)).max(0.0);
        (kin * 2.0 * b * b * big_r * big_r / (m * r * r * (6.0 * PI * PI * r * r + b * b))).sqrt()
    }

    /// `r''` from eq. (7) at radius `r` (m/s^2).
    pub fn rddot(&self, r: f64) -> f64 {
        let (b, g) = (self.p.thickness_m, self.p.g_m_s2);
        let rd = self.rdot(r);
        let k = 6.0 * PI * PI * r * r;
        -((2.0 * k + b * b) * rd * rd + 3.0 * b * b * g * r) / ((k + b * b) * r)
    }

    /// R: the outer radius (m).
    pub fn params(&self) -> Params {
        self.p
    }

    /// R (m).
    pub fn outer_radius_m(&self) -> f64 {
        self.p.outer_radius_m
    }

    /// Total energy E of eq. (5), corrected per ERRATA A1 (J).
    pub fn energy_j(&self) -> f64 {
        self.energy_j
    }

    /// Time at which the radius reaches `r`, or `None` past the cutoff.
    pub fn time_at_radius(&self, r: f64) -> Option<f64> {
        self.traj.time_at(r)
    }

    /// The state at radius `r`.
    pub fn state_at_radius(&self, r: f64, t_s: f64) -> RefState {
        let (big_r, b, m, g) = (
            self.p.outer_radius_m,
            self.p.thickness_m,
            self.p.mass_kg,
            self.p.g_m_s2,
        );
        let rd = self.rdot(r);
        let potential_j = m * g * r.powi(3) / (big_r * big_r);
        RefState {
            t_s,
            laid_fraction: 1.0 - (r / big_r).powi(2),
            r_m: r,
            x_m: PI * (big_r * big_r - r * r) / b,
            xdot_m_s: 2.0 * PI * r * rd / b,
            omega_rad_s: 2.0 * PI * rd / b,
            kinetic_j: (self.energy_j - potential_j).max(0.0),
            potential_j,
        }
    }

    /// The state at time `t`, or `None` past the cutoff.
    pub fn state_at_time(&self, t: f64) -> Option<RefState> {
        self.traj.q_at(t).map(|r| self.state_at_radius(r, t))
    }

    /// Normal force of the floor on the coil (N), exact form of eq. (9) (ERRATA A4):
    /// `N_tot = m g + M r b^2 (r'^2 - 3 g r) / (R^2 (6 pi^2 r^2 + b^2))`.
    pub fn normal_force_n(&self, r: f64) -> f64 {
        let (big_r, b, m, g) = (
            self.p.outer_radius_m,
            self.p.thickness_m,
            self.p.mass_kg,
            self.p.g_m_s2,
        );
        let rd = self.rdot(r);
        m * g * r * r / (big_r * big_r)
            + m * r * b * b * (rd * rd - 3.0 * g * r)
                / (big_r * big_r * (6.0 * PI * PI * r * r + b * b))
    }

    /// Horizontal force on the coil (N), eq. (11) in its exact form
    /// `F_tot = -2 pi M r^2 (3 r'^2 + r r'') / (b R^2)`; the Lagrange-multiplier force (30)
    /// equals it once its sign slip is corrected (ERRATA A6).
    pub fn horizontal_force_n(&self, r: f64) -> f64 {
        let (big_r, b, m) = (self.p.outer_radius_m, self.p.thickness_m, self.p.mass_kg);
        let rd = self.rdot(r);
        -2.0 * PI * m * r * r * (3.0 * rd * rd + r * self.rddot(r)) / (b * big_r * big_r)
    }
}

/// Closed form of eq. (7) from rest in the limit `r >> b`:
/// `t(r) = 2 pi sqrt(R^3 - r^3) / (b sqrt(3 g))` (s).
pub fn continuum_time_from_rest(p: &Params, r: f64) -> f64 {
    2.0 * PI * (p.outer_radius_m.powi(3) - r.powi(3)).sqrt()
        / (p.thickness_m * (3.0 * p.g_m_s2).sqrt())
}

/// The force/torque equation of motion (17), `3 r r'' + 10 r'^2 = 0`, which has no `g`.
///
/// ```text
/// r' r^(10/3) = r0' R^(10/3),   t(r) = 3 R / (13 |r0'|) (1 - (r/R)^(13/3))     ERRATA C2
/// ```
/// It does not conserve the energy (5) when g != 0, and from rest it never moves.
#[derive(Debug, Clone, Copy)]
pub struct ForceTorque {
    p: Params,
    rdot0: f64,
}

impl ForceTorque {
    /// The closed-form solution of eq. (17) from the scene's push.
    pub fn new(p: Params) -> Self {
        Self {
            p,
            rdot0: p.thickness_m * p.push_speed_m_s / (2.0 * PI * p.outer_radius_m),
        }
    }

    /// Time at which the radius reaches `r` (s).
    pub fn time_at_radius(&self, r: f64) -> f64 {
        let big_r = self.p.outer_radius_m;
        3.0 * big_r / (13.0 * self.rdot0) * (1.0 - (r / big_r).powf(13.0 / 3.0))
    }

    /// `|r'|` at radius `r` (m/s).
    pub fn rdot(&self, r: f64) -> f64 {
        self.rdot0 * (self.p.outer_radius_m / r).powf(10.0 / 3.0)
    }

    /// The radius at time `t`, `None` once the coil is gone (`t >= 3R / (13 |r0'|)`).
    pub fn radius_at_time(&self, t: f64) -> Option<f64> {
        let big_r = self.p.outer_radius_m;
        let s = 1.0 - t * 13.0 * self.rdot0 / (3.0 * big_r);
        (s > 0.0).then(|| big_r * s.powf(3.0 / 13.0))
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use approx::assert_relative_eq;

    /// The yoga mat's parameters, pushed at `push` (m/s).
    pub(crate) fn yoga(push: f64) -> Params {
        Params {
            outer_radius_m: 0.06,
            thickness_m: 0.005,
            mass_kg: 1.5,
            core_radius_m: 0.0,
            g_m_s2: 9.81,
            push_speed_m_s: push,
        }
    }

    /// The thin tape's parameters, pushed at `push` (m/s).
    pub(crate) fn thin(push: f64) -> Params {
        Params {
            outer_radius_m: 0.03,
            thickness_m: 0.0001,
            mass_kg: 0.2,
            core_radius_m: 0.0,
            g_m_s2: 9.81,
            push_speed_m_s: push,
        }
    }

    #[test]
    fn continuum_from_near_rest_matches_the_closed_form_for_a_thin_tape() {
        // t(r) = 2 pi sqrt(R^3 - r^3) / (b sqrt(3 g)) holds for r >> b and r0' -> 0; the
        // b^2 terms of (6) and the tiny push shift it by well under 0.1 % here.
        let p = thin(1e-7);
        let c = Continuum::new(p, 0.001);
        for r in [0.025, 0.015, 0.005] {
            let t = c.time_at_radius(r).unwrap();
            let closed = continuum_time_from_rest(&p, r);
            assert!(
                (t / closed - 1.0).abs() < 1e-3,
                "r = {r}: quadrature {t:.6} s, closed form {closed:.6} s"
            );
        }
    }

    #[test]
    fn continuum_energy_is_conserved_and_its_derivative_is_eq7() {
        let p = yoga(0.3);
        let c = Continuum::new(p, 0.002);
        for r in [0.055, 0.03, 0.01, 0.003] {
            let s = c.state_at_radius(r, 0.0);
            assert_relative_eq!(
                s.kinetic_j + s.potential_j,
                c.energy_j(),
                max_relative = 1e-12
            );
            // Check (7) against a finite difference of r'(r): r'' = r' d(r')/dr.
            let h = 1e-7;
            let rd = c.rdot(r);
            let fd = -rd * (c.rdot(r + h) - c.rdot(r - h)) / (2.0 * h);
            // Moving inward: r' = -|r'|, so r'' = d(r')/dt = (d|r'|/dr) |r'|... sign below.
            assert_relative_eq!(c.rddot(r), -fd, max_relative = 1e-5);
        }
    }

    #[test]
    fn continuum_time_and_state_lookups_invert_each_other() {
        let c = Continuum::new(yoga(0.3), 0.002);
        for r in [0.059, 0.045, 0.02, 0.004] {
            let t = c.time_at_radius(r).unwrap();
            let s = c.state_at_time(t).unwrap();
            assert_relative_eq!(s.r_m, r, max_relative = 1e-9);
        }
        assert!(c.time_at_radius(0.001).is_none());
    }

    #[test]
    fn continuum_quadrature_agrees_with_a_direct_integration_of_eq7() {
        // Integrate (7) as an ODE with a small fixed-step RK4 and compare t at r = R/4.
        let p = yoga(0.3);
        let c = Continuum::new(p, 0.002);
        let rdot0 = -p.thickness_m * p.push_speed_m_s / (2.0 * PI * p.outer_radius_m);
        let f = |r: f64, v: f64| {
            let (b, g) = (p.thickness_m, p.g_m_s2);
            let k = 6.0 * PI * PI * r * r;
            [
                v,
                -((2.0 * k + b * b) * v * v + 3.0 * b * b * g * r) / ((k + b * b) * r),
            ]
        };
        let (mut r, mut v, mut t) = (p.outer_radius_m, rdot0, 0.0);
        let dt = 1e-5;
        let target = 0.015;
        while r > target {
            let k1 = f(r, v);
            let k2 = f(r + 0.5 * dt * k1[0], v + 0.5 * dt * k1[1]);
            let k3 = f(r + 0.5 * dt * k2[0], v + 0.5 * dt * k2[1]);
            let k4 = f(r + dt * k3[0], v + dt * k3[1]);
            let rn = r + dt / 6.0 * (k1[0] + 2.0 * k2[0] + 2.0 * k3[0] + k4[0]);
            let vn = v + dt / 6.0 * (k1[1] + 2.0 * k2[1] + 2.0 * k3[1] + k4[1]);
            if rn <= target {
                t += dt * (r - target) / (r - rn);
                r = target;
            } else {
                r = rn;
                v = vn;
                t += dt;
            }
        }
        let q = c.time_at_radius(target).unwrap();
        assert_relative_eq!(q, t, max_relative = 1e-6);
    }

    #[test]
    fn force_torque_closed_form_solves_eq17() {
        let ft = ForceTorque::new(yoga(0.3));
        // 3 r r'' + 10 r'^2 = 0 with r' = -|r'|: check by finite differences of r(t).
        let t = 1.0;
        let h = 1e-4;
        let r = ft.radius_at_time(t).unwrap();
        let rp =
            (ft.radius_at_time(t + h).unwrap() - ft.radius_at_time(t - h).unwrap()) / (2.0 * h);
        let rpp = (ft.radius_at_time(t + h).unwrap() - 2.0 * r + ft.radius_at_time(t - h).unwrap())
            / (h * h);
        let residual = 3.0 * r * rpp + 10.0 * rp * rp;
        assert!(
            residual.abs() < 1e-6 * 10.0 * rp * rp,
            "residual {residual}"
        );
        assert_relative_eq!(ft.time_at_radius(r), t, max_relative = 1e-9);
        assert_relative_eq!(-rp, ft.rdot(r), max_relative = 1e-6);
    }
}
