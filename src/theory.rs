//! The theory layer: the paper's analytic references and the exact-geometry model, pure
//! `f64` with the seed's equation numbers and the ERRATA ids. It reads a validated
//! [`Scene`] and the [`spiral`](crate::spiral) geometry; it never steps an engine, never
//! runs a loop and never writes a file. [`References`] is built once per scene and passed
//! on to the run and its outputs.

pub mod continuum;
pub mod exact;
pub mod folded;
pub mod forces;
pub mod rivals;
mod trajectory;

use std::sync::Arc;

use crate::scene::Scene;
use continuum::{Continuum, ForceTorque, Params};
use exact::ExactGeometry;
use forces::{ForceFn, force_reference};
use rivals::{Rival, SpoolGeometry, rivals_with};

/// The analytic references of a scene.
pub struct References {
    /// Eq. (7).
    pub continuum: Continuum,
    /// Eq. (17).
    pub force_torque: ForceTorque,
    /// The exact-geometry model, tabulated once and shared with the exact rival.
    pub exact: Arc<ExactGeometry>,
    /// The paper's rivals for the scene's case; at most one is the valid reference.
    pub rivals: Vec<Rival>,
    /// The case's analytic constraint forces.
    pub forces: Option<ForceFn>,
    /// Spools: `l / r`, the angle of the whole tape (rad).
    pub theta_per_fraction: Option<f64>,
    /// The floor's friction coefficient for the exact-geometry model's force split
    /// (infinite on a sticky floor); `None` on a fixed axis, which has no floor.
    pub floor_grip: Option<f64>,
}

impl References {
    /// The scene's valid reference among the rivals, if it has one.
    pub fn valid(&self) -> Option<&Rival> {
        self.rivals.iter().find(|r| r.valid)
    }

    /// Builds and tabulates the references for a scene, down to half the bang radius.
    pub fn new(scene: &Scene) -> Self {
        let p = params(scene);
        let r_end = 0.5 * scene.stop.bang_radius_m;
        let exact = Arc::new(exact_geometry(scene));
        Self {
            continuum: Continuum::new(p, r_end),
            force_torque: ForceTorque::new(p),
            rivals: rivals_with(scene, &exact),
            exact,
            forces: force_reference(scene),
            theta_per_fraction: (scene.tape.core_radius_m > 0.0).then(|| {
                let sg = SpoolGeometry::of(scene);
                sg.l_m / sg.r_m
            }),
            floor_grip: match (scene.axis.fixed, scene.floor.sticky) {
                (true, _) => None,
                (false, true) => Some(f64::INFINITY),
                (false, false) => Some(scene.floor.friction),
            },
        }
    }
}

/// The exact-geometry model of a scene, on its slope or sliding on a frictionless floor,
/// tabulated to half the bang radius (a solid coil) or to 99.5 % laid (a spool).
pub fn exact_geometry(scene: &Scene) -> ExactGeometry {
    let (p, slope) = (params(scene), scene.floor.slope_deg.to_radians());
    let f_end = if scene.tape.core_radius_m > 0.0 {
        0.995
    } else {
        1.0 - (0.5 * scene.stop.bang_radius_m / scene.tape.outer_radius_m).powi(2)
    };
    if scene.floor.friction <= 0.0 {
        ExactGeometry::frictionless(p, f_end)
    } else {
        ExactGeometry::to_fraction(p, slope, f_end)
    }
}

/// The reference parameters of a scene.
pub fn params(scene: &Scene) -> Params {
    Params {
        outer_radius_m: scene.tape.outer_radius_m,
        thickness_m: scene.tape.thickness_m,
        mass_kg: scene.tape.mass_kg,
        core_radius_m: scene.tape.core_radius_m,
        g_m_s2: scene.gravity.g_m_s2,
        push_speed_m_s: scene.push.contact_speed_m_s,
    }
}
