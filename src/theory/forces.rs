//! The constraint forces on the coil the paper derives for each case, as functions of the
//! laid fraction: the total upward force `N_tot` and the total horizontal force `F_tot`
//! (floor plus laid tape, +x positive). Pure `f64`; this module neither simulates nor prints.
//!
//! The simulation's counterpart is the momentum balance of the moving bodies over a sample
//! interval, `N_tot = dP_y/dt + m g cos(a)`, `F_tot = dP_x/dt - m g sin(a)` with `m` the coil's
//! mass: the impulses the floor and the resting tape delivered, as in eqs. (9), (11), (46),
//! (63)-(66), (85)-(86).

use std::f64::consts::PI;

use crate::scene::Scene;
use crate::theory::continuum::Continuum;
use crate::theory::params;
use crate::theory::rivals::{Case, SpoolGeometry, single_turn_spin, slope_energy_rdot, spool_rate};

/// `(N_tot, F_tot)` in N at a laid fraction, `None` where the reference does not exist.
pub type ForceFn = Box<dyn Fn(f64) -> Option<(f64, f64)> + Send + Sync>;

/// The paper's constraint forces for a scene's case; `None` for the fixed axis (no floor)
/// and the frictionless cases,
/// whose floor exerts no horizontal force by construction.
///
/// ```text
/// coil:        N_tot = m g + M r b^2 (r'^2 - 3 g r) / (R^2 (6 pi^2 r^2 + b^2))     (9), A4
///              F_tot = -2 pi M r^2 (3 r'^2 + r r'') / (b R^2)                       (11), A6, A7
/// slope:       N = M g r^2 cos(a) / R^2 + M r (2 r'^2 + r r'') / R^2                (64)
///              F_x = -M g r^2 sin(a) / R^2 - 2 pi M r^2 (3 r'^2 + r r'') / (b R^2)  (66), with (72) A11
/// single turn: N = m g - (M r / 2 pi) [theta'' (1 - cos) + theta'^2 sin]            (46)
///              F = (M r / 2 pi) [theta'' (2 pi - theta + sin) - theta'^2 (1 - cos)]  d/dt of P_x, (40)
/// spool:       N = M g (1 - u)                                                       (85)
///              F_tot = M (1 - u) r theta'' - M r^2 theta'^2 / l                      (86), A16
///                    = M g r (l - 2 r theta) / (2 l (l - r theta)) from rest: zero at r theta = l/2
/// ```
pub fn force_reference(scene: &Scene) -> Option<ForceFn> {
    let p = params(scene);
    let (big_r, b, m, g) = (p.outer_radius_m, p.thickness_m, p.mass_kg, p.g_m_s2);
    let radius = move |f: f64| big_r * (1.0 - f).max(0.0).sqrt();
    match Case::of(scene) {
        Case::Coil | Case::ZeroG => {
            let c = Continuum::new(p, 0.5 * scene.stop.bang_radius_m);
            Some(Box::new(move |f| {
                let r = radius(f);
                c.time_at_radius(r)?;
                Some((c.normal_force_n(r), c.horizontal_force_n(r)))
            }))
        }
        Case::Slope => {
            let a = scene.floor.slope_deg.to_radians();
            let rdot = slope_energy_rdot(p, a);
            Some(Box::new(move |f| {
                let r = radius(f);
                let rd = rdot(r);
                if !rd.is_finite() || f >= 1.0 {
                    return None;
                }
                // r'' from eq. (72) with the 2 pi coefficient (ERRATA A11).
                let k = 6.0 * PI * PI * r * r;
                let rr = -((2.0 * k + b * b) * rd * rd
                    + 3.0 * b * b * g * r * a.cos()
                    + 2.0 * PI * g * b * r * r * a.sin())
                    / (k + b * b);
                let n = m * g * r * r * a.cos() / (big_r * big_r)
                    + m * r * (2.0 * rd * rd + rr) / (big_r * big_r);
                let f_up = m * g * r * r * a.sin() / (big_r * big_r)
                    + 2.0 * PI * m * r * r * (3.0 * rd * rd + rr) / (b * big_r * big_r);
                Some((n, -f_up))
            }))
        }
        Case::SingleTurn => {
            let sg = SpoolGeometry::of(scene);
            let r = sg.r_m;
            let spin = single_turn_spin(r, g, sg.spin0_rad_s);
            Some(Box::new(move |f| {
                if f >= 1.0 {
                    return None;
                }
                let th = 2.0 * PI * f;
                let w = spin(th);
                let (s, c) = th.sin_cos();
                let keep = 2.0 * PI - th + s;
                let acc = (w * w + g / r) * (1.0 - c) / (2.0 * keep);
                let mass = m * (1.0 - f);
                let n = mass * g - m * r / (2.0 * PI) * (acc * (1.0 - c) + w * w * s);
                let fx = m * r / (2.0 * PI) * (acc * keep - w * w * (1.0 - c));
                Some((n, fx))
            }))
        }
        Case::Spool => {
            let sg = SpoolGeometry::of(scene);
            let (r, l) = (sg.r_m, sg.l_m);
            let rate = spool_rate(r, l, g, sg.spin0_rad_s);
            Some(Box::new(move |u| {
                if u >= 1.0 {
                    return None;
                }
                let w = rate(u) * l / r;
                let acc = (g / l + r * w * w / l) / (2.0 * (1.0 - u));
                let n = m * g * (1.0 - u);
                let fx = m * (1.0 - u) * r * acc - m * r * r * w * w / l;
                Some((n, fx))
            }))
        }
        Case::FrictionlessSpool | Case::FrictionlessCoil | Case::Vertical => None,
    }
}

/// The laid fraction at which `F_tot` first changes sign, scanning `[0, f_max]`.
pub fn sign_change_fraction(forces: &ForceFn, f_max: f64) -> Option<f64> {
    let n = 4000;
    let mut prev: Option<(f64, f64)> = None;
    for k in 0..=n {
        let f = f_max * f64::from(k) / f64::from(n);
        let Some((_, fx)) = forces(f) else { continue };
        if let Some((f0, x0)) = prev
            && x0.signum() != fx.signum()
            && x0 != 0.0
        {
            return Some(f0 + (f - f0) * x0 / (x0 - fx));
        }
        prev = Some((f, fx));
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn scene(text: &str) -> Scene {
        Scene::from_toml_str(text, "t").expect("valid scene")
    }

    #[test]
    fn spool_force_from_near_rest_is_errata_a16_and_changes_sign_at_half() {
        // ERRATA A16: F_tot = M g r (l - 2 r theta) / (2 l (l - r theta)), zero at u = 1/2.
        let text = "[tape]\nouter_radius_m = 0.020040788736\nthickness_m = 2e-6\nmass_kg = 0.1\n\
                    core_radius_m = 0.019959211264\n[push]\ncontact_speed_m_s = 2e-12\n\
                    [stop]\nbang_radius_m = 0.02\n";
        let s = scene(text);
        let f = force_reference(&s).unwrap();
        let sg = SpoolGeometry::of(&s);
        let (r, l, m, g) = (sg.r_m, sg.l_m, 0.1, 9.81);
        for u in [0.1, 0.3, 0.7, 0.9] {
            let th = u * l / r;
            let a16 = m * g * r * (l - 2.0 * r * th) / (2.0 * l * (l - r * th));
            let (n, fx) = f(u).unwrap();
            assert_relative_eq!(fx, a16, max_relative = 1e-6);
            assert_relative_eq!(n, m * g * (1.0 - u), max_relative = 1e-12);
        }
        let half = sign_change_fraction(&f, 0.99).unwrap();
        assert!((half - 0.5).abs() < 1e-3, "sign change at u = {half}");
    }

    #[test]
    fn level_coil_sign_change_moves_earlier_with_a_push() {
        // Eq. (11) from rest changes sign at r = (2/5)^(1/3) R, f = 1 - (2/5)^(2/3) = 0.457;
        // a push adds -2 pi M R^2 r0'^2 / (b r^2) (ERRATA A7) and moves it earlier.
        let rest = scene(
            "[tape]\nouter_radius_m = 0.03\nthickness_m = 0.0001\nmass_kg = 0.2\n\
             [push]\ncontact_speed_m_s = 1e-6\n",
        );
        let f_rest = sign_change_fraction(&force_reference(&rest).unwrap(), 0.99).unwrap();
        assert!(
            (f_rest - (1.0 - 0.4f64.powf(2.0 / 3.0))).abs() < 0.01,
            "f = {f_rest}"
        );
        let pushed = scene(
            "[tape]\nouter_radius_m = 0.03\nthickness_m = 0.0001\nmass_kg = 0.2\n\
             [push]\ncontact_speed_m_s = 0.1\n",
        );
        let f_push = sign_change_fraction(&force_reference(&pushed).unwrap(), 0.99).unwrap();
        // A7's approximate form vanishes at (r/R)^3 = 2/5 + 3 v^2 / (10 g R) for a push v.
        let a7 = 1.0 - (0.4_f64 + 0.3 * 0.1 * 0.1 / (9.81 * 0.03)).powf(2.0 / 3.0);
        assert!(
            f_push < f_rest && (f_push - a7).abs() < 0.002,
            "pushed {f_push}, A7 {a7}, from rest {f_rest}"
        );
    }

    #[test]
    fn single_turn_forces_start_at_the_weight_and_the_rolling_push() {
        // At theta = 0 the whole ring rolls: N = M g and F = M r theta'' with
        // theta'' = 0 (eq. 45 at theta = 0), so F = 0.
        let s = Scene::from_file(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/scenes/single-turn.toml"
        ))
        .expect("valid scene");
        let (n, fx) = force_reference(&s).unwrap()(0.0).unwrap();
        assert_relative_eq!(n, 0.05 * 9.81, max_relative = 1e-9);
        assert!(fx.abs() < 1e-12, "F = {fx}");
    }
}
