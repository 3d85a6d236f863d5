//! The wound tape's midline as an Archimedean spiral: points, tangents, arc length,
//! curvature, mass moments and the link nodes placed on it. Pure `f64`, no engine types.
//!
//! Body frame: the spiral centre is the origin and the spiral winds clockwise as its
//! parameter `psi` grows outward, `p(psi) = a psi (cos psi, -sin psi)` with `a = b / (2 pi)`,
//! so that the pitch (the distance between neighbouring turns) is the tape thickness `b`.
//! With the tangent of growing `psi` pointing along -x at the bottom, the coil sits above
//! the floor and rolls towards +x while it sheds tape to its left. This module does not know
//! about the floor, time or the engine.

use std::f64::consts::PI;

/// Five-point Gauss-Legendre nodes on [-1, 1].
const GL_X: [f64; 5] = [
    0.0,
    -0.538_469_310_105_683_1,
    0.538_469_310_105_683_1,
    -0.906_179_845_938_664,
    0.906_179_845_938_664,
];
/// Five-point Gauss-Legendre weights.
const GL_W: [f64; 5] = [
    0.568_888_888_888_888_9,
    0.478_628_670_499_366_5,
    0.478_628_670_499_366_5,
    0.236_926_885_056_189_1,
    0.236_926_885_056_189_1,
];

/// Integrates `f` over `[lo, hi]` with one five-point Gauss-Legendre panel (exact for
/// polynomials of degree 9).
pub fn gauss5(lo: f64, hi: f64, f: impl Fn(f64) -> f64) -> f64 {
    let half = 0.5 * (hi - lo);
    let mid = 0.5 * (hi + lo);
    GL_X.iter()
        .zip(GL_W.iter())
        .map(|(x, w)| w * f(mid + half * x))
        .sum::<f64>()
        * half
}

/// An Archimedean spiral of pitch `thickness_m` between the parameters `psi_in` and `psi_out`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Spiral {
    /// `a = b / (2 pi)`: radius gained per radian (m/rad).
    pub a_m: f64,
    /// Parameter (rad) of the inner end of the midline.
    pub psi_in: f64,
    /// Parameter (rad) of the outer end of the midline.
    pub psi_out: f64,
}

impl Spiral {
    /// The midline of a tape of thickness `b` wound from `core_radius` to `outer_radius`
    /// (outer surface): it runs from radius `core + b/2` to radius `R - b/2`.
    pub fn wound(outer_radius_m: f64, thickness_m: f64, core_radius_m: f64) -> Self {
        let a_m = thickness_m / (2.0 * PI);
        Self {
            a_m,
            psi_in: (core_radius_m + 0.5 * thickness_m) / a_m,
            psi_out: (outer_radius_m - 0.5 * thickness_m) / a_m,
        }
    }

    /// Radius of the midline at parameter `psi` (m).
    pub fn radius(&self, psi: f64) -> f64 {
        self.a_m * psi
    }

    /// The parameter at which the midline has radius `rho`.
    pub fn psi_at_radius(&self, rho: f64) -> f64 {
        rho / self.a_m
    }

    /// Point of the midline in the body frame (m).
    pub fn point(&self, psi: f64) -> [f64; 2] {
        let (s, c) = psi.sin_cos();
        [self.a_m * psi * c, -self.a_m * psi * s]
    }

    /// Derivative of [`Self::point`] with respect to `psi` (m/rad).
    pub fn tangent(&self, psi: f64) -> [f64; 2] {
        let (s, c) = psi.sin_cos();
        [self.a_m * (c - psi * s), -self.a_m * (s + psi * c)]
    }

    /// Arc length from the spiral centre (`psi = 0`) to `psi` (m):
    /// `s = (a/2) (psi sqrt(1 + psi^2) + asinh psi)`.
    pub fn arc_from_centre(&self, psi: f64) -> f64 {
        0.5 * self.a_m * (psi * (1.0 + psi * psi).sqrt() + psi.asinh())
    }

    /// Arc length between two parameters (m), positive when `hi > lo`.
    pub fn arc(&self, lo: f64, hi: f64) -> f64 {
        self.arc_from_centre(hi) - self.arc_from_centre(lo)
    }

    /// Total midline length (m).
    pub fn length(&self) -> f64 {
        self.arc(self.psi_in, self.psi_out)
    }

    /// Radius of curvature of the midline at `psi` (m): `a (1 + psi^2)^(3/2) / (2 + psi^2)`.
    pub fn curvature_radius(&self, psi: f64) -> f64 {
        let q = 1.0 + psi * psi;
        self.a_m * q * q.sqrt() / (1.0 + q)
    }

    /// Centre of curvature of the midline at `psi`, in the body frame (m).
    pub fn curvature_centre(&self, psi: f64) -> [f64; 2] {
        let p = self.point(psi);
        let t = self.tangent(psi);
        let n = t[0].hypot(t[1]);
        // The spiral turns clockwise: the centre of curvature lies to the right of the tangent.
        let rc = self.curvature_radius(psi);
        [p[0] + rc * t[1] / n, p[1] - rc * t[0] / n]
    }

    /// Direction angle (rad) of the tangent of growing `psi`, continuous in `psi`:
    /// `-(psi + pi/2 - atan(1/psi))`. It turns at the rate
    /// `d(angle)/d(psi) = -(2 + psi^2) / (1 + psi^2)`.
    pub fn tangent_angle(&self, psi: f64) -> f64 {
        -(psi + 0.5 * PI - (1.0 / psi).atan())
    }

    /// `|d(tangent angle)/d(psi)| = (2 + psi^2) / (1 + psi^2)`: the coil turns this much
    /// faster than the peel point moves along the spiral parameter.
    pub fn turn_rate(psi: f64) -> f64 {
        (2.0 + psi * psi) / (1.0 + psi * psi)
    }

    /// Body rotation (rad) that makes the tangent at `psi` point along -x, i.e. that puts
    /// the point `psi` at the bottom of the coil with the laid tape leaving to the left.
    pub fn rotation_with_bottom_at(&self, psi: f64) -> f64 {
        PI - self.tangent_angle(psi)
    }

    /// The parameter of the lowest midline point of a coil rotated by `rotation` (rad),
    /// searched by Newton's method from `guess` (the lowest point of the previous step).
    pub fn lowest_psi(&self, rotation: f64, guess: f64) -> f64 {
        // Solve rotation_with_bottom_at(psi) = rotation (mod 2 pi) near the guess.
        let mut psi = guess;
        let target = rotation;
        for _ in 0..30 {
            let mut err = self.rotation_with_bottom_at(psi) - target;
            err -= (err / (2.0 * PI)).round() * 2.0 * PI;
            let step = err / Self::turn_rate(psi);
            psi -= step;
            if step.abs() < 1e-13 * psi.abs().max(1.0) {
                break;
            }
        }
        psi
    }

    /// Node parameters of links that divide each turn into `links_per_turn` equal angles,
    /// from the outer end inward; the innermost link ends at `psi_in` and may be shorter.
    pub fn link_nodes(&self, links_per_turn: u32) -> Vec<f64> {
        let step = 2.0 * PI / f64::from(links_per_turn);
        let mut nodes = vec![self.psi_out];
        let mut k = 1u64;
        loop {
            let psi = self.psi_out - step * k as f64;
            if psi <= self.psi_in + 0.25 * step {
                nodes.push(self.psi_in);
                break;
            }
            nodes.push(psi);
            k += 1;
        }
        nodes
    }
}

/// Rotates a body-frame vector by `angle` (rad).
pub fn rotate(v: [f64; 2], angle: f64) -> [f64; 2] {
    let (s, c) = angle.sin_cos();
    [c * v[0] - s * v[1], s * v[0] + c * v[1]]
}

/// Points of a curve in the spiral's body frame, and where that frame stands in the world:
/// turned by `rotation_rad` counter-clockwise about the body origin, which sits at
/// `origin_m`. A wound coil is rigid, so its points stay the same while it rolls; only the
/// pose moves.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Placed {
    /// Where the body origin (the spiral centre) is in the world (m).
    pub origin_m: [f64; 2],
    /// Rotation of the body frame (rad), counter-clockwise.
    pub rotation_rad: f64,
    /// The curve in the body frame (m).
    pub points_m: Vec<[f64; 2]>,
}

impl Placed {
    /// Where the body-frame point `p` is in the world (m).
    pub fn to_world(&self, p: [f64; 2]) -> [f64; 2] {
        let q = rotate(p, self.rotation_rad);
        [self.origin_m[0] + q[0], self.origin_m[1] + q[1]]
    }

    /// The curve in the world frame (m).
    pub fn world_points(&self) -> Vec<[f64; 2]> {
        self.points_m.iter().map(|&p| self.to_world(p)).collect()
    }
}

/// Cumulative mass moments of a uniform line mass along the spiral midline: the mass, first
/// moment and second moment (about the spiral centre) of the part between `psi_in` and
/// `psi`, per unit line density. Tabulated once, evaluated anywhere to quadrature accuracy.
#[derive(Debug, Clone)]
pub struct SpiralMoments {
    spiral: Spiral,
    step: f64,
    /// `[length, first_x, first_y, second]` at each table node.
    table: Vec<[f64; 4]>,
}

impl SpiralMoments {
    /// Tabulates the moments on panels of at most 0.25 rad.
    pub fn new(spiral: Spiral) -> Self {
        let span = spiral.psi_out - spiral.psi_in;
        let panels = ((span / 0.25).ceil() as usize).max(1);
        let step = span / panels as f64;
        let mut table = Vec::with_capacity(panels + 1);
        let mut acc = [0.0; 4];
        table.push(acc);
        for k in 0..panels {
            let lo = spiral.psi_in + step * k as f64;
            let add = Self::panel(&spiral, lo, lo + step);
            for (a, d) in acc.iter_mut().zip(add) {
                *a += d;
            }
            table.push(acc);
        }
        Self {
            spiral,
            step,
            table,
        }
    }

    fn panel(spiral: &Spiral, lo: f64, hi: f64) -> [f64; 4] {
        let mut out = [0.0; 4];
        let a = spiral.a_m;
        let ds = |psi: f64| a * (1.0 + psi * psi).sqrt();
        out[0] = spiral.arc(lo, hi);
        out[1] = gauss5(lo, hi, |psi| spiral.point(psi)[0] * ds(psi));
        out[2] = gauss5(lo, hi, |psi| spiral.point(psi)[1] * ds(psi));
        out[3] = gauss5(lo, hi, |psi| a * a * psi * psi * ds(psi));
        out
    }

    /// The midline's length between `psi_in` and `psi`: [`Self::at`]`(psi)[0]`, bit for bit,
    /// without the three moments' quadratures.
    pub fn length_at(&self, psi: f64) -> f64 {
        self.length_at_near(psi, &mut None)
    }

    /// [`Self::length_at`], bit for bit, for many `psi` in a row: `start` keeps the panel
    /// last used and its start's arc from the spiral's centre, which need not be made again.
    pub fn length_at_near(&self, psi: f64, start: &mut Option<(usize, f64)>) -> f64 {
        let psi = psi.clamp(self.spiral.psi_in, self.spiral.psi_out);
        let k =
            (((psi - self.spiral.psi_in) / self.step).floor() as usize).min(self.table.len() - 1);
        let lo = self.spiral.psi_in + self.step * k as f64;
        let base = self.table[k][0];
        if psi <= lo {
            return base;
        }
        let from_centre = match *start {
            Some((j, arc)) if j == k => arc,
            _ => {
                let arc = self.spiral.arc_from_centre(lo);
                *start = Some((k, arc));
                arc
            }
        };
        // `Spiral::arc(lo, psi)`, with the first term kept.
        base + (self.spiral.arc_from_centre(psi) - from_centre)
    }

    /// The `psi` at which the midline's length from `psi_in` is `length` (m), clamped to the
    /// spiral: the inverse of [`Self::length_at`]. The panel is found among the table's nodes,
    /// then Newton's method on the panel's closed-form arc, whose slope `a sqrt(1 + psi^2)` is
    /// known, converges to the last bits in a few steps: the bisection it replaces took about
    /// sixty evaluations of the arc.
    pub fn psi_at_length(&self, length: f64) -> f64 {
        let (psi_in, psi_out) = (self.spiral.psi_in, self.spiral.psi_out);
        let last = self.table.len() - 1;
        if length.is_nan() || length <= 0.0 || last == 0 {
            return psi_in;
        }
        if length >= self.table[last][0] {
            return psi_out;
        }
        // The last node at or below `length` starts the panel holding it.
        let k = (self.table.partition_point(|row| row[0] <= length).max(1) - 1).min(last - 1);
        let lo = psi_in + self.step * k as f64;
        let hi = (lo + self.step).min(psi_out);
        let base = self.table[k][0];
        let share = (length - base) / (self.table[k + 1][0] - base);
        let mut psi = lo + share.clamp(0.0, 1.0) * (hi - lo);
        for _ in 0..50 {
            let miss = base + self.spiral.arc(lo, psi) - length;
            let next = (psi - miss / (self.spiral.a_m * (1.0 + psi * psi).sqrt())).clamp(lo, hi);
            if next == psi {
                break;
            }
            let settled = (next - psi).abs() <= 4.0 * f64::EPSILON * psi.abs();
            psi = next;
            if settled {
                break;
            }
        }
        psi
    }

    /// `[length, first_x, first_y, second]` of the midline between `psi_in` and `psi`.
    pub fn at(&self, psi: f64) -> [f64; 4] {
        let psi = psi.clamp(self.spiral.psi_in, self.spiral.psi_out);
        let k =
            (((psi - self.spiral.psi_in) / self.step).floor() as usize).min(self.table.len() - 1);
        let lo = self.spiral.psi_in + self.step * k as f64;
        let base = self.table[k];
        if psi <= lo {
            return base;
        }
        let add = Self::panel(&self.spiral, lo, psi);
        [
            base[0] + add[0],
            base[1] + add[1],
            base[2] + add[2],
            base[3] + add[3],
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn yoga() -> Spiral {
        Spiral::wound(0.06, 0.005, 0.0)
    }

    #[test]
    fn length_at_is_the_first_moment_bit_for_bit() {
        let m = SpiralMoments::new(yoga());
        let s = yoga();
        for k in 0..=200 {
            let psi = s.psi_in + (s.psi_out - s.psi_in) * f64::from(k) / 200.0;
            assert_eq!(
                m.length_at(psi).to_bits(),
                m.at(psi)[0].to_bits(),
                "psi = {psi}"
            );
        }
        // And with the panel's start kept, in any order of psi.
        let mut start = None;
        for k in 0..=2000_u32 {
            let psi = s.psi_in + (s.psi_out - s.psi_in) * f64::from((k * 7919) % 2001) / 2000.0;
            assert_eq!(
                m.length_at_near(psi, &mut start).to_bits(),
                m.length_at(psi).to_bits(),
                "psi = {psi}"
            );
        }
    }

    #[test]
    fn yoga_mat_midline_is_shorter_than_the_continuum_length() {
        // From the centre to R - b/2 the midline is 2.080 m (a figure derived for the core
        // issue), against pi R^2 / b = 2.262 m for the continuum coil.
        let s = yoga();
        assert_relative_eq!(s.arc_from_centre(s.psi_out), 2.080, epsilon = 5e-4);
        // Our midline starts at radius b/2: the innermost half turn is not tape.
        assert!(s.length() < 2.080 && s.length() > 2.07, "{}", s.length());
    }

    #[test]
    fn arc_length_matches_quadrature_of_the_tangent() {
        let s = yoga();
        let n = 2000;
        let h = (s.psi_out - s.psi_in) / f64::from(n);
        let mut sum = 0.0;
        for k in 0..n {
            let lo = s.psi_in + h * f64::from(k);
            sum += gauss5(lo, lo + h, |p| {
                let t = s.tangent(p);
                t[0].hypot(t[1])
            });
        }
        assert_relative_eq!(sum, s.length(), max_relative = 1e-12);
    }

    #[test]
    fn tangent_angle_and_turn_rate_agree_with_the_tangent_vector() {
        let s = yoga();
        for psi in [3.5, 10.0, 40.0, 72.0] {
            let t = s.tangent(psi);
            let ang = t[1].atan2(t[0]);
            let mut d = ang - s.tangent_angle(psi);
            d -= (d / (2.0 * PI)).round() * 2.0 * PI;
            assert!(d.abs() < 1e-12, "psi {psi}: angle off by {d}");
            let h = 1e-5;
            let rate = (s.tangent_angle(psi + h) - s.tangent_angle(psi - h)) / (2.0 * h);
            assert_relative_eq!(-rate, Spiral::turn_rate(psi), max_relative = 1e-8);
        }
    }

    #[test]
    fn lowest_point_is_found_after_a_rotation() {
        let s = yoga();
        let psi0 = 50.0;
        // Rolling towards +x turns the coil clockwise: its rotation angle falls.
        let rot = s.rotation_with_bottom_at(psi0) - 0.3;
        let psi = s.lowest_psi(rot, psi0);
        // The rotated tangent at the lowest point is horizontal, pointing -x.
        let t = rotate(s.tangent(psi), rot);
        assert!(t[1].abs() < 1e-12 * t[0].abs(), "tangent {t:?}");
        assert!(t[0] < 0.0);
        assert!(psi < psi0, "rolling forward moves the lowest point inward");
    }

    #[test]
    fn curvature_centre_is_at_the_curvature_radius_and_above_the_bottom() {
        let s = yoga();
        let psi = 30.0;
        let rot = s.rotation_with_bottom_at(psi);
        let p = rotate(s.point(psi), rot);
        let c = rotate(s.curvature_centre(psi), rot);
        assert_relative_eq!(c[0], p[0], epsilon = 1e-12);
        assert_relative_eq!(c[1] - p[1], s.curvature_radius(psi), max_relative = 1e-12);
    }

    #[test]
    fn moments_of_a_full_table_match_direct_quadrature() {
        let s = yoga();
        let m = SpiralMoments::new(s);
        let psi = 41.3;
        let direct = SpiralMoments::panel(&s, s.psi_in, psi);
        // One panel is not accurate over many turns; compare against a fine sum instead.
        let n = 4000;
        let h = (psi - s.psi_in) / f64::from(n);
        let mut fine = [0.0; 4];
        for k in 0..n {
            let lo = s.psi_in + h * f64::from(k);
            let p = SpiralMoments::panel(&s, lo, lo + h);
            for i in 0..4 {
                fine[i] += p[i];
            }
        }
        let got = m.at(psi);
        assert_relative_eq!(got[0], fine[0], max_relative = 1e-12);
        assert_relative_eq!(got[0], direct[0], max_relative = 1e-12);
        assert_relative_eq!(got[3], fine[3], max_relative = 1e-10);
        assert!((got[1] - fine[1]).abs() < 1e-10 && (got[2] - fine[2]).abs() < 1e-10);
    }

    #[test]
    fn link_nodes_step_by_one_link_angle_and_end_at_the_inner_end() {
        let s = yoga();
        let nodes = s.link_nodes(32);
        assert_relative_eq!(nodes[0], s.psi_out);
        assert_relative_eq!(*nodes.last().unwrap(), s.psi_in);
        assert_relative_eq!(nodes[0] - nodes[1], 2.0 * PI / 32.0, max_relative = 1e-12);
        assert!(nodes.windows(2).all(|w| w[1] < w[0]));
    }
}
