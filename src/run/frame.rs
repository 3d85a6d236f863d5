//! What the run loop hands to observers besides samples: [`Frame`]s (the geometry of the
//! tape and of the analytic "ghost" coils at one instant, for drawing) and [`Event`]s
//! (detaches, the final bang, warnings). Pure `f64` geometry; it draws nothing itself and
//! knows no file format.

use std::f64::consts::PI;

use serde::Serialize;

use crate::spiral::{Placed, rotate};
use crate::theory::{continuum::Continuum, exact::ExactGeometry};

/// The coil of eq. (7) drawn as a disc: eq. (7) knows only its radius and its contact
/// position, and rolling without slip fixes its rotation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GhostDisc {
    /// Centre (m): `(x_ref, r_ref)`, the disc standing on the floor `y = 0`.
    pub centre_m: [f64; 2],
    /// Radius `r` of eq. (7) (m).
    pub radius_m: f64,
    /// Counter-clockwise rotation since the push (rad). The contact line has moved by the
    /// laid length `pi (R^2 - r^2) / b` (eq. 1) at `dx = r dtheta`, so the coil has turned
    /// clockwise by `2 pi (R - r) / b`: one turn per thickness shed.
    pub rotation_rad: f64,
}

impl GhostDisc {
    /// The eq. (7) coil at time `t_s`, `None` past its tabulated end.
    pub fn at(continuum: &Continuum, thickness_m: f64, t_s: f64) -> Option<Self> {
        let s = continuum.state_at_time(t_s)?;
        Some(Self {
            centre_m: [s.x_m, s.r_m],
            radius_m: s.r_m,
            rotation_rad: -2.0 * PI * (continuum.outer_radius_m() - s.r_m) / thickness_m,
        })
    }
}

/// The exact-geometry model's coil: the wound part of the midline spiral, placed with its
/// lowest point on the laid tape's midline at the model's contact position.
#[derive(Debug, Clone, PartialEq)]
pub struct GhostSpiral {
    /// Contact position (m).
    pub contact_m: [f64; 2],
    /// The wound midline in the spiral's body frame from its inner end out to the contact
    /// point, `points_per_turn` per turn at fixed parameters, so that only the outer end
    /// changes from one instant to the next; placed where the model's coil is.
    pub spiral: Placed,
}

/// The exact model's wound midline at fixed parameters, `points_per_turn` a turn from its
/// inner end out: computed once, and each instant's [`GhostSpiral`] draws the part of it still
/// wound.
#[derive(Debug, Clone)]
pub struct SpiralGrid {
    /// The spiral parameters, increasing.
    psi: Vec<f64>,
    /// The midline's points at them, in the spiral's body frame (m).
    points_m: Vec<[f64; 2]>,
}

impl SpiralGrid {
    /// The grid of the exact model's spiral.
    pub fn new(exact: &ExactGeometry, points_per_turn: u32) -> Self {
        let spiral = exact.spiral();
        let step = 2.0 * PI / f64::from(points_per_turn.max(3));
        let psi: Vec<f64> = (0..)
            .map(|k| spiral.psi_in + f64::from(k) * step)
            .take_while(|&q| q < spiral.psi_out)
            .collect();
        let points_m = psi.iter().map(|&q| spiral.point(q)).collect();
        Self { psi, points_m }
    }
}

impl GhostSpiral {
    /// The exact-geometry coil at time `t_s`, `None` past its tabulated end: the grid's points
    /// inside the contact parameter, then the contact point.
    pub fn at(
        exact: &ExactGeometry,
        grid: &SpiralGrid,
        thickness_m: f64,
        t_s: f64,
    ) -> Option<Self> {
        let psi = exact.psi_at_time(t_s)?;
        let spiral = exact.spiral();
        let rotation = spiral.rotation_with_bottom_at(psi);
        let low = rotate(spiral.point(psi), rotation);
        let contact = [spiral.arc(psi, spiral.psi_out), 0.5 * thickness_m];
        let inner = grid.psi.partition_point(|&q| q < psi);
        let mut points_m = Vec::with_capacity(inner + 1);
        points_m.extend_from_slice(&grid.points_m[..inner]);
        points_m.push(spiral.point(psi));
        Some(Self {
            contact_m: contact,
            spiral: Placed {
                origin_m: [contact[0] - low[0], contact[1] - low[1]],
                rotation_rad: rotation,
                points_m,
            },
        })
    }
}

/// The tape and its references at one instant, for drawing. Coordinates in metres in the
/// world frame: x along the floor, y up, the floor surface at `y = 0`.
#[derive(Debug, Clone, PartialEq)]
pub struct Frame {
    /// Simulated time (s).
    pub t_s: f64,
    /// Contact-line position of the simulation, `x_m` of its sample (m).
    pub contact_x_m: f64,
    /// Nodes of the links that left the coil (laid, hanging or in the bang), from the outer
    /// end; consecutive nodes bound a link.
    pub off_coil_m: Vec<[f64; 2]>,
    /// Nodes of the links still wound on the coil, in the coil's body frame from the
    /// innermost outward, placed where the coil is; no points once it is released.
    pub on_coil: Placed,
    /// The coil of eq. (7), `None` past its end.
    pub eq7: Option<GhostDisc>,
    /// The exact-geometry model's coil, `None` past its end.
    pub exact: Option<GhostSpiral>,
}

/// Something that happened at one instant of a run.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Event {
    /// Links left the coil during one step (usually one link; a fast step may shed more).
    Detach {
        /// Simulated time (s).
        t_s: f64,
        /// Index of the first link that left in this step, 0 = the outer end.
        first_link: usize,
        /// Number of links that left in this step.
        links: usize,
        /// Links off the coil after this step.
        detached: usize,
        /// Energy lost by these detaches (J), negative if gained.
        energy_lost_j: f64,
    },
    /// The coil reached the bang radius and its links were released as a free chain.
    BangStart {
        /// Simulated time of the last rolling step (s).
        t_s: f64,
        /// Kinetic energy carried into the bang (J).
        kinetic_j: f64,
        /// Mechanical energy above the flat rest state (J).
        available_j: f64,
    },
    /// The bang ended, at rest or at its cap: the end of the run.
    BangEnd {
        /// Simulated time (s).
        t_s: f64,
        /// When the bang began (s).
        started_s: f64,
        /// Energy dissipated from the start of the bang on (J).
        dissipated_j: f64,
        /// What ended it.
        ended_by: crate::model::BangEnd,
    },
    /// Something a user should know about the run.
    Warning {
        /// Simulated time (s).
        t_s: f64,
        /// What happened.
        message: String,
    },
}

impl Event {
    /// The event's simulated time (s).
    pub fn t_s(&self) -> f64 {
        match self {
            Event::Detach { t_s, .. }
            | Event::BangStart { t_s, .. }
            | Event::BangEnd { t_s, .. }
            | Event::Warning { t_s, .. } => *t_s,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::theory::continuum::Params;

    fn params() -> Params {
        Params {
            outer_radius_m: 0.06,
            thickness_m: 0.005,
            mass_kg: 1.5,
            core_radius_m: 0.0,
            g_m_s2: 9.81,
            push_speed_m_s: 0.3,
        }
    }

    #[test]
    fn eq7_disc_starts_whole_on_the_floor_with_no_turn() {
        let c = Continuum::new(params(), 0.0025);
        let d = GhostDisc::at(&c, 0.005, 0.0).expect("t = 0 is tabulated");
        assert!((d.radius_m - 0.06).abs() < 1e-9, "r = {}", d.radius_m);
        assert!(
            (d.centre_m[1] - d.radius_m).abs() < 1e-12,
            "stands on y = 0"
        );
        assert!(d.rotation_rad.abs() < 1e-6, "rotation {}", d.rotation_rad);
        assert!(GhostDisc::at(&c, 0.005, 100.0).is_none(), "past the end");
    }

    #[test]
    fn exact_spiral_touches_the_midline_at_its_contact() {
        let e = ExactGeometry::new(params(), 0.0025);
        let grid = SpiralGrid::new(&e, 32);
        let g = GhostSpiral::at(&e, &grid, 0.005, 1.0).expect("t = 1 s is tabulated");
        // Its last point, placed, is the contact; no point dips below the laid midline
        // y = b/2.
        let world = g.spiral.world_points();
        let contact = world.last().unwrap();
        assert!((contact[0] - g.contact_m[0]).abs() < 1e-12);
        assert!((contact[1] - g.contact_m[1]).abs() < 1e-12);
        let lowest = world.iter().map(|p| p[1]).fold(f64::INFINITY, f64::min);
        assert!(
            lowest > 0.0025 - 1e-4,
            "lowest point {lowest:.6} m, expected >= b/2 = 0.0025 m"
        );
    }
}
