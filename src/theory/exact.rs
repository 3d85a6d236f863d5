//! The exact-geometry model: the rigid Archimedean spiral the links form, rolling without
//! slip on its midline (or sliding at zero momentum on a frictionless floor), energy
//! conserved; its motion, its constraint forces from its momentum (`N_tot`, `F_tot` and
//! their least-pull split into `F` and `F_int`), its angular momentum, and where it would
//! need a floor that pulls (its hop onset). Pure `f64`, no engine types; it does not
//! simulate contact, and the paper's continuum equations are in [`continuum`](super::continuum).

use std::sync::OnceLock;

use serde::Serialize;

use super::continuum::{Params, RefState};
use super::trajectory::Trajectory;
use crate::spiral::{Spiral, SpiralMoments, rotate};

/// The exact-geometry energy model: the rigid Archimedean spiral that the links form
/// (midline mass, pitch `b`), rolling without slip on its midline with the laid tape at
/// rest (midline at height `b/2`), energy conserved. This is what the contact-resolved
/// model converges to as the links shrink and the time step falls.
///
/// ```text
/// q = psi (spiral parameter at the peel point), zero-velocity point = midline peel point
/// omega = psi' (2 + psi^2) / (1 + psi^2),   x' = a sqrt(1 + psi^2) psi',  a = b / (2 pi)
/// E = I_P(psi) omega^2 / 2 + g [m(psi) y_cm(psi) + (M - m(psi)) b / 2] = E0
/// ```
/// `I_P` is the coil's moment of inertia about the peel point. This model differs from the
/// continuum (7) at first order in `b/R`.
///
/// On a slope of angle `alpha` (positive when +x is downhill, App. B) gravity is tilted,
/// `g = g (sin alpha, -cos alpha)`, and the potential energy is `-m g.p` of the coil and of the
/// laid tape, which lies from `x = 0` to the peel point `x = s(psi)` (the laid arc length):
/// ```text
/// V = g cos(alpha) [m y_cm + (M - m) b / 2] - g sin(alpha) [m x_cm + lambda s^2 / 2]
/// ```
#[derive(Debug, Clone)]
pub struct ExactGeometry {
    p: Params,
    /// `g sin(alpha)`, along +x (m/s^2).
    g_along: f64,
    /// `g cos(alpha)`, towards the floor (m/s^2).
    g_perp: f64,
    /// Frictionless floor: the coil slides, the flat tape slides back as a whole, and the
    /// total horizontal momentum stays zero (see [`Self::frictionless`]).
    sliding: bool,
    spiral: Spiral,
    moments: SpiralMoments,
    line_density_kg_m: f64,
    energy_j: f64,
    /// Sliding: the conserved horizontal moment of [`Self::sliding_moment`] at the start.
    sliding_moment0: f64,
    traj: Trajectory,
    /// [`Self::hop_onset_fraction`], scanned on its first call and kept: the run, its
    /// guard and its report all ask for it.
    hop_onset: OnceLock<Option<f64>>,
}

/// The exact-geometry model's constraint forces at one instant (N, up and +x positive).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct GeoForces {
    /// Everything but gravity on the spiral, upward: `N_tot`.
    pub n_tot_n: f64,
    /// Everything but gravity on the spiral, along +x: `F_tot = F + F_int`.
    pub f_tot_n: f64,
    /// The floor's friction on the spiral, `F`.
    pub f_floor_n: f64,
    /// The laid tape's pull on the spiral through its end, `F_int`.
    pub f_int_n: f64,
}

/// The exact model's spiral in motion: its pose, clockwise spin `omega` (rad/s), centre of
/// mass from the peel point `c` (m) and momentum (kg m/s).
#[derive(Debug, Clone, Copy)]
struct Motion {
    pose: Pose,
    spin: f64,
    c: [f64; 2],
    momentum: [f64; 2],
}

/// Geometry of the coil with its lowest point at a given spiral parameter.
#[derive(Debug, Clone, Copy)]
struct Pose {
    mass_kg: f64,
    /// Moment of inertia about the peel point (kg m^2).
    inertia_peel: f64,
    /// Height of the coil's centre of mass (m).
    y_cm: f64,
    /// Horizontal position of the coil's centre of mass, from the tape's outer end (m).
    x_cm: f64,
    /// Laid length, the peel point's x (m).
    laid_m: f64,
}

impl ExactGeometry {
    /// Tabulates the model from the full coil down to the parameter where the continuum
    /// equivalent radius `R sqrt(1 - f)` reaches `r_end_m`.
    pub fn new(p: Params, r_end_m: f64) -> Self {
        Self::on_slope(p, 0.0, r_end_m)
    }

    /// As [`Self::new`], on a floor sloping by `slope_rad` (positive: +x downhill).
    pub fn on_slope(p: Params, slope_rad: f64, r_end_m: f64) -> Self {
        Self::to_fraction(p, slope_rad, 1.0 - (r_end_m / p.outer_radius_m).powi(2))
    }

    /// As [`Self::on_slope`], tabulated up to the laid fraction `f_end` (for a spool, whose
    /// laid fraction is not `1 - (r/R)^2`).
    pub fn to_fraction(p: Params, slope_rad: f64, f_end: f64) -> Self {
        Self::build(p, slope_rad, f_end, false)
    }

    /// The same rigid spiral on a frictionless level floor (App. D), started spinning in
    /// place at the push speed. The material at the contact slips at a speed `u` along the
    /// floor, the flat tape, attached there, slides back with it (its material velocity,
    /// ERRATA A18, A19), and the total horizontal momentum stays zero. With `c` the coil's
    /// centre of mass relative to the peel point and `omega` its spin:
    /// ```text
    /// m (u - omega c_y) + (M - m) u = 0                 =>  u = omega m c_y / M
    /// T = [m ((u - omega c_y)^2 + omega^2 c_x^2) + I_cm omega^2 + (M - m) u^2] / 2
    /// ```
    /// which for a thin spool (`c = (0, r)`, `I_cm = m r^2`) is A18's `M r^2 theta'^2 (1 - u^2) / 2`.
    /// Energy is conserved. Tabulated to `f_end`.
    pub fn frictionless(p: Params, f_end: f64) -> Self {
        Self::build(p, 0.0, f_end, true)
    }

    fn build(p: Params, slope_rad: f64, f_end: f64, sliding: bool) -> Self {
        let spiral = Spiral::wound(p.outer_radius_m, p.thickness_m, p.core_radius_m);
        let moments = SpiralMoments::new(spiral);
        let line_density_kg_m = p.mass_kg / spiral.length();
        let (sin_a, cos_a) = slope_rad.sin_cos();
        let mut model = Self {
            p,
            g_along: p.g_m_s2 * sin_a,
            g_perp: p.g_m_s2 * cos_a,
            sliding,
            spiral,
            moments,
            line_density_kg_m,
            energy_j: 0.0,
            sliding_moment0: 0.0,
            traj: Trajectory::empty(spiral.psi_out),
            hop_onset: OnceLock::new(),
        };
        let psi0 = spiral.psi_out;
        let psidot0 = p.push_speed_m_s / (spiral.a_m * (1.0 + psi0 * psi0).sqrt());
        let pose0 = model.pose(psi0);
        model.energy_j = 0.5 * model.inertia_psi(psi0, &pose0) * psidot0 * psidot0
            + model.potential(psi0, &pose0);
        model.sliding_moment0 = model.sliding_moment(&pose0);
        let psi_end = model.psi_at_fraction(f_end);
        let traj = Trajectory::new_parallel(psi0, psi_end, 6000, |psi| model.psidot(psi));
        model.traj = traj;
        model
    }

    /// The spiral the model rolls.
    pub fn spiral(&self) -> &Spiral {
        &self.spiral
    }

    /// Total energy (J).
    pub fn energy_j(&self) -> f64 {
        self.energy_j
    }

    fn pose(&self, psi: f64) -> Pose {
        let [len, fx, fy, second] = self.moments.at(psi);
        let lam = self.line_density_kg_m;
        let p = self.spiral.point(psi);
        let mass_kg = lam * len;
        let inertia_peel =
            lam * (second - 2.0 * (p[0] * fx + p[1] * fy) + len * (p[0] * p[0] + p[1] * p[1]));
        let rot = self.spiral.rotation_with_bottom_at(psi);
        let rel = if len > 0.0 {
            rotate([fx / len - p[0], fy / len - p[1]], rot)
        } else {
            [0.0, 0.0]
        };
        let laid_m = self.spiral.arc(psi, self.spiral.psi_out);
        Pose {
            mass_kg,
            inertia_peel,
            y_cm: 0.5 * self.p.thickness_m + rel[1],
            x_cm: laid_m + rel[0],
            laid_m,
        }
    }

    fn potential(&self, _psi: f64, pose: &Pose) -> f64 {
        let g = self.g_perp;
        let across = g
            * (pose.mass_kg * pose.y_cm
                + (self.p.mass_kg - pose.mass_kg) * 0.5 * self.p.thickness_m);
        let along =
            pose.mass_kg * pose.x_cm + 0.5 * self.line_density_kg_m * pose.laid_m * pose.laid_m;
        across - self.g_along * along
    }

    /// `|psi'|` from the energy integral (rad/s).
    fn psidot(&self, psi: f64) -> f64 {
        self.psidot_at(psi, &self.pose(psi))
    }

    /// [`Self::psidot`] with the pose at `psi` already made.
    fn psidot_at(&self, psi: f64, pose: &Pose) -> f64 {
        let kin = (self.energy_j - self.potential(psi, pose)).max(0.0);
        (2.0 * kin / self.inertia_psi(psi, pose)).sqrt()
    }

    /// `2 T / psi'^2` (kg m^2): `I_P w^2` when rolling, the sliding form of
    /// [`Self::frictionless`] otherwise.
    fn inertia_psi(&self, psi: f64, pose: &Pose) -> f64 {
        let w = Spiral::turn_rate(psi);
        if !self.sliding {
            return pose.inertia_peel * w * w;
        }
        let (m, big_m) = (pose.mass_kg, self.p.mass_kg);
        let c = [
            pose.x_cm - pose.laid_m,
            pose.y_cm - 0.5 * self.p.thickness_m,
        ];
        let i_cm = pose.inertia_peel - m * (c[0] * c[0] + c[1] * c[1]);
        // Slip speed of the contact material point over the spin, from zero momentum.
        let mu = m * c[1] / big_m;
        w * w * (m * ((mu - c[1]).powi(2) + c[0] * c[0]) + i_cm + (big_m - m) * mu * mu)
    }

    /// Laid mass fraction when the lowest point is at `psi`.
    pub fn laid_fraction(&self, psi: f64) -> f64 {
        1.0 - self.moments.length_at(psi) / self.spiral.length()
    }

    /// The spiral parameter of the lowest point at laid fraction `f`, by bisection to the last
    /// bit (it stops once the midpoint is one of the ends). The references differentiate in
    /// `psi` and tabulate the moments in panels, so a last-bit change of `psi` can move a
    /// force far more than its own rounding: the bisection is kept, bit for bit, and only
    /// guided. Newton's
    /// method ([`SpiralMoments::psi_at_length`]) finds the root first; a midpoint farther
    /// from it than the margin falls on the side the root says without evaluating the arc,
    /// so some fifteen evaluations replace sixty. The margin is 1e-11 of `psi`, and never
    /// less than eight steps of the test's own rounding: `1 - length / total` moves in steps
    /// of `EPSILON`, which near the core of a tape of a thousand turns span more `psi` than
    /// 1e-11 of it.
    pub fn psi_at_fraction(&self, f: f64) -> f64 {
        let total = self.spiral.length();
        let guess = self.moments.psi_at_length((1.0 - f) * total);
        let rounding = f64::EPSILON * total / (self.spiral.a_m * (1.0 + guess * guess).sqrt());
        let margin = 1e-11 * guess.abs().max(1.0) + 8.0 * rounding;
        // `laid_fraction(mid)`, bit for bit, its panel's start kept from one midpoint to the
        // next.
        let mut start = None;
        let (mut lo, mut hi) = (self.spiral.psi_in, self.spiral.psi_out);
        for _ in 0..100 {
            let mid = 0.5 * (lo + hi);
            if mid == lo || mid == hi {
                break;
            }
            let short_of_root = if mid < guess - margin {
                true
            } else if mid > guess + margin {
                false
            } else {
                1.0 - self.moments.length_at_near(mid, &mut start) / total > f
            };
            if short_of_root {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        0.5 * (lo + hi)
    }

    /// [`Self::psi_at_fraction`] unguided, every midpoint evaluated: to check it against.
    #[cfg(test)]
    fn psi_at_fraction_by_bisection(&self, f: f64) -> f64 {
        let (mut lo, mut hi) = (self.spiral.psi_in, self.spiral.psi_out);
        for _ in 0..100 {
            let mid = 0.5 * (lo + hi);
            if mid == lo || mid == hi {
                break;
            }
            if self.laid_fraction(mid) > f {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        0.5 * (lo + hi)
    }

    /// Time at which the laid fraction reaches `f`, `None` past the tabulated end.
    pub fn time_at_fraction(&self, f: f64) -> Option<f64> {
        self.traj.time_at(self.psi_at_fraction(f))
    }

    /// Whether the model slides (frictionless floor) rather than rolls.
    pub fn is_sliding(&self) -> bool {
        self.sliding
    }

    /// Sliding on a frictionless floor: the peel point's x, measured from where it started,
    /// with the total horizontal momentum zero, so the centre of mass of the coil and the
    /// laid tape stays put (eqs. 100, 106 for a centred coil; here with the spiral's own
    /// off-centre mass). `None` for a rolling model, whose peel point is at the laid length.
    pub fn sliding_contact_x(&self, psi: f64) -> Option<f64> {
        self.sliding
            .then(|| (self.sliding_moment(&self.pose(psi)) - self.sliding_moment0) / self.p.mass_kg)
    }

    /// `(M - m) s / 2 - m (x_cm - s)`: how far the whole tape's mass lies behind the peel
    /// point, times `M` (`s` the laid length, `m` the coil's mass, `x_cm - s` its centre
    /// ahead of the peel point). At zero momentum `M x_peel - this` is conserved.
    fn sliding_moment(&self, pose: &Pose) -> f64 {
        let laid_mass = self.p.mass_kg - pose.mass_kg;
        0.5 * laid_mass * pose.laid_m - pose.mass_kg * (pose.x_cm - pose.laid_m)
    }

    /// The state with the lowest point at `psi`.
    pub fn state_at_psi(&self, psi: f64, t_s: f64) -> RefState {
        let pose = self.pose(psi);
        let potential_j = self.potential(psi, &pose);
        let psidot = self.psidot_at(psi, &pose);
        let f = self.laid_fraction(psi);
        RefState {
            t_s,
            laid_fraction: f,
            r_m: self.p.outer_radius_m * (1.0 - f).max(0.0).sqrt(),
            // Sliding, the contact line is not the laid length.
            x_m: self
                .sliding_contact_x(psi)
                .unwrap_or_else(|| self.spiral.arc(psi, self.spiral.psi_out)),
            xdot_m_s: self.xdot(psi, psidot),
            omega_rad_s: Spiral::turn_rate(psi) * psidot,
            kinetic_j: (self.energy_j - potential_j).max(0.0),
            potential_j,
        }
    }

    /// The state at time `t`, `None` past the tabulated end.
    pub fn state_at_time(&self, t: f64) -> Option<RefState> {
        self.traj.q_at(t).map(|psi| self.state_at_psi(psi, t))
    }

    /// Contact-line speed with the lowest point at `psi`, `a sqrt(1 + psi^2) psi'` (m/s);
    /// `NaN` when sliding (the contact line is not the laid length).
    pub fn xdot_at_psi(&self, psi: f64) -> f64 {
        self.xdot(psi, self.psidot(psi))
    }

    fn xdot(&self, psi: f64, psidot: f64) -> f64 {
        if self.sliding {
            f64::NAN
        } else {
            self.spiral.a_m * (1.0 + psi * psi).sqrt() * psidot
        }
    }

    /// The spiral parameter of the lowest point at time `t`, `None` past the tabulated end.
    pub fn psi_at_time(&self, t: f64) -> Option<f64> {
        self.traj.q_at(t)
    }

    /// The spiral's motion with its lowest point at `psi`: every point of it turns about the
    /// peel point, so with `c` its centre of mass from there and `omega` its clockwise spin,
    /// its momentum is `P = m omega (c_y, -c_x)`. Sliding, `P_x` is `NaN`: the material at
    /// the contact slides along the floor, which adds nothing to `P_y`.
    fn motion(&self, psi: f64) -> Motion {
        let pose = self.pose(psi);
        let spin = Spiral::turn_rate(psi) * self.psidot_at(psi, &pose);
        let c = [
            pose.x_cm - pose.laid_m,
            pose.y_cm - 0.5 * self.p.thickness_m,
        ];
        let m = pose.mass_kg;
        let p_x = if self.sliding {
            f64::NAN
        } else {
            m * spin * c[1]
        };
        Motion {
            pose,
            spin,
            c,
            momentum: [p_x, -m * spin * c[0]],
        }
    }

    /// Angular momentum of the rolling spiral about the origin, the laid tape's outer end on
    /// the floor's contact plane `(0, b/2)`, counter-clockwise (kg m^2/s): `r x P` of its
    /// centre of mass plus its spin about it, `-I_cm omega`. `None` when sliding.
    pub fn angular_momentum_o(&self, psi: f64) -> Option<f64> {
        if self.sliding {
            return None;
        }
        let Motion {
            pose,
            spin,
            c,
            momentum: p,
        } = self.motion(psi);
        let i_cm = pose.inertia_peel - pose.mass_kg * (c[0] * c[0] + c[1] * c[1]);
        Some(pose.x_cm * p[1] - c[1] * p[0] - i_cm * spin)
    }

    /// `(F_tot, N_tot)` of the spiral from the rate of change of its momentum (see
    /// [`Self::motion`]), by central differences in `psi` (N). Sliding, `F_tot` is `NaN`.
    fn force_from_momentum(&self, psi: f64) -> [f64; 2] {
        let h = 1e-4;
        let p1 = self.motion(psi + h).momentum;
        let p0 = self.motion(psi - h).momentum;
        // psi falls as the spiral rolls: psi' = -|psi'|.
        let pose = self.pose(psi);
        let rate = -self.psidot_at(psi, &pose) / (2.0 * h);
        let m = pose.mass_kg;
        [
            (p1[0] - p0[0]) * rate - m * self.g_along,
            (p1[1] - p0[1]) * rate + m * self.g_perp,
        ]
    }

    /// The floor's normal force on the rolling spiral with its lowest point at `psi`, `N_tot`
    /// of [`Self::forces`] (N). The spiral's centre of mass sits about `b / pi` off its
    /// axis, tied to the outer end, which is always at the peel point: that offset is why
    /// the momentum is not `m` times the rate of change of the wound mass's centre (the
    /// shed tape takes its share of the first moment with it). `N` falls below zero only
    /// near the end, when the coil's centre accelerates downward faster than `g`; from
    /// there a rigid spiral on a floor that cannot pull would hop, and this model no longer
    /// applies. Sliding on a frictionless floor, the same.
    pub fn normal_force_n(&self, psi: f64) -> f64 {
        self.force_from_momentum(psi)[1]
    }

    /// The constraint forces on the rolling spiral with its lowest point at `psi` (N), from
    /// its momentum `P = m omega (c_y, -c_x)`: the tape it sheds leaves at the peel point, where
    /// the velocity is zero, and carries no momentum away, so `dP/dt` is the force of
    /// everything but gravity.
    ///
    /// ```text
    /// N_tot = dP_y/dt + m g cos(a),   F_tot = dP_x/dt - m g sin(a),   d/dt = psi' d/dpsi
    /// ```
    /// The floor and the laid tape act at the same point, the peel point, so the rigid model
    /// gives their sum only. The laid tape is flexible and leaves the floor level there: it
    /// pulls along the floor (`N_int = 0`, `N = N_tot`). Of `F_tot` the split given is the
    /// one with the least pull in the laid tape: the floor's friction carries it while it
    /// can, `|F| <= mu N`, and the laid tape the rest. The simulation's split converges to
    /// it as the links shrink (docs/variants.md gives the measured gaps). `None`
    /// when sliding or at the table's ends.
    pub fn forces(&self, psi: f64, friction: f64) -> Option<GeoForces> {
        let (lo, hi) = (self.traj.q_end(), self.spiral.psi_out);
        if self.sliding || psi - 1e-4 <= lo || psi + 1e-4 >= hi {
            return None;
        }
        let [f_tot, n_tot] = self.force_from_momentum(psi);
        // A sticky floor (infinite friction) holds whatever it must.
        let grip = if friction.is_infinite() {
            f64::INFINITY
        } else {
            friction * n_tot.max(0.0)
        };
        let floor = f_tot.clamp(-grip, grip);
        Some(GeoForces {
            n_tot_n: n_tot,
            f_tot_n: f_tot,
            f_floor_n: floor,
            f_int_n: f_tot - floor,
        })
    }

    /// The first laid fraction at which the rolling spiral would need a floor that pulls
    /// (`N < 0`), scanning the tabulated motion; `None` if it never does. The scan runs
    /// once, on the first call; later calls return its result.
    pub fn hop_onset_fraction(&self) -> Option<f64> {
        *self.hop_onset.get_or_init(|| self.scan_hop_onset())
    }

    /// The scan of [`Self::hop_onset_fraction`]: the first of 20,000 steps of `psi` over the
    /// table where the normal force is below zero. Every 16th step is tried first, then the
    /// steps before the first of those that hops: the same step as trying all of them, unless
    /// the force dips below zero and back within 16 steps before it (`N` falls smoothly to
    /// the hop; a test checks the shipped scenes against the full scan).
    fn scan_hop_onset(&self) -> Option<f64> {
        const STEPS: u32 = 20_000;
        const STRIDE: usize = 16;
        let (start, end) = (self.spiral.psi_out, self.traj.q_end());
        let psi = |k: u32| start - (start - end) * f64::from(k) / f64::from(STEPS);
        let hops = |k: u32| self.normal_force_n(psi(k)) < 0.0;
        let coarse = (1..STEPS)
            .step_by(STRIDE)
            .chain(std::iter::once(STEPS - 1))
            .find(|&k| hops(k))?;
        let from = coarse.saturating_sub(STRIDE as u32 - 1).max(1);
        (from..=coarse)
            .find(|&k| hops(k))
            .map(|k| self.laid_fraction(psi(k)))
    }

    /// The first laid fraction at which the rolling spiral's outer turn asks the tape for
    /// more tension than it has, scanning 4000 steps of `psi` over the table; `None` if it
    /// never does, or where the model slides.
    ///
    /// The rigid spiral carries its outer turn round with it. At the top of the coil that
    /// turn moves about the centre at `omega r`, and stays on the turn below only while its
    /// tension `T` and gravity's pull towards the centre give the centripetal force: the
    /// layer below can push it out, never pull it in:
    /// ```text
    /// T / r + lambda g cos(a) >= lambda omega^2 r   <=>   T >= lambda (omega^2 r^2 - g cos(a) r)
    /// ```
    /// A tape with no bending stiffness (the paper's, and the chain's) has no tension at the
    /// top but what the laid tape's pull `-F_int` brings round (friction between the layers
    /// can pass tension along, not make it from none). Where the need exceeds that pull the
    /// outer turn of a floppy tape lifts off its coil at the top: the rigid coil holds it
    /// there by a force the tape cannot give, and from here on it stands for a tape that is
    /// stiff (or set in its coil) enough to stay wound.
    pub fn loosen_onset_fraction(&self, friction: f64) -> Option<f64> {
        const STEPS: u32 = 4000;
        if self.sliding {
            return None;
        }
        let (start, end) = (self.spiral.psi_out, self.traj.q_end());
        (1..STEPS).find_map(|k| {
            let psi = start - (start - end) * f64::from(k) / f64::from(STEPS);
            let pull = -self.forces(psi, friction)?.f_int_n;
            (self.outer_turn_tension_n(psi) > pull.max(0.0)).then(|| self.laid_fraction(psi))
        })
    }

    /// The tension the rolling spiral's outer turn needs at the coil's top to stay on the
    /// turn below, `lambda (omega^2 r^2 - g cos(a) r)` (N; see
    /// [`Self::loosen_onset_fraction`]).
    pub fn outer_turn_tension_n(&self, psi: f64) -> f64 {
        let r = self.spiral.radius(psi);
        let omega = Spiral::turn_rate(psi) * self.psidot(psi);
        self.line_density_kg_m * (omega * omega * r * r - self.g_perp * r)
    }

    /// [`Self::scan_hop_onset`] trying every step, to check it against.
    #[cfg(test)]
    fn scan_hop_onset_every_step(&self) -> Option<f64> {
        let (start, end) = (self.spiral.psi_out, self.traj.q_end());
        let n = 20_000;
        (1..n).find_map(|k| {
            let psi = start - (start - end) * f64::from(k) / f64::from(n);
            (self.normal_force_n(psi) < 0.0).then(|| self.laid_fraction(psi))
        })
    }
}

#[cfg(test)]
mod tests;
