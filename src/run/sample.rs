//! One row of output, [`Sample`]: the simulation at an instant with its references beside
//! it, built from the model's observation and the scene's [`References`]; the forces are
//! the means over a [`ForceWindow`](crate::run::force_window::ForceWindow). It steps nothing
//! and writes nothing.

use std::f64::consts::PI;

use serde::Serialize;

use crate::model::{Observation, Phase};
use crate::run::force_window::WindowMean;
use crate::theory::References;

/// One row of output: the simulation and its references at the same instant.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct Sample {
    /// Simulated time (s).
    pub t_s: f64,
    /// Mass on the floor over the total mass.
    pub laid_fraction: f64,
    /// Continuum-equivalent coil radius `R sqrt(1 - laid_fraction)` (m).
    pub r_m: f64,
    /// Contact-line position (m).
    pub x_m: f64,
    /// Contact-line speed (m/s), from the change of `x_m` over the last step.
    pub xdot_m_s: f64,
    /// Clockwise spin of the coil (rad/s).
    pub omega_rad_s: f64,
    /// Kinetic energy of everything that moves (J).
    pub kinetic_j: f64,
    /// Potential energy of the whole tape above the floor (J).
    pub potential_j: f64,
    /// Energy dissipated so far, `E0 - kinetic - potential` (J).
    pub dissipated_j: f64,
    /// Floor normal force on everything that moves (the coil and the laid links not yet
    /// frozen), its contact impulses summed over the sample interval over the interval (N).
    pub normal_n: f64,
    /// Floor horizontal force on everything that moves, +x positive, likewise (N).
    pub friction_n: f64,
    /// Loss inside engine steps while rolling (J).
    pub lost_step_j: f64,
    /// Loss at detach events (J).
    pub lost_detach_j: f64,
    /// Kinetic energy discarded by freezing laid links while rolling (J).
    pub lost_freeze_j: f64,
    /// Loss since the final bang began (J).
    pub lost_bang_j: f64,
    /// Final bang: dissipated against the floor's normal impulses so far (J).
    pub bang_floor_normal_j: f64,
    /// Final bang: dissipated against the floor's friction impulses so far (J).
    pub bang_floor_friction_j: f64,
    /// Final bang: dissipated against the normal impulses between the tape's own layers so
    /// far (J).
    pub bang_layers_normal_j: f64,
    /// Final bang: dissipated against the friction between the tape's own layers so far (J).
    pub bang_layers_friction_j: f64,
    /// Final bang: dissipated against the joint impulses so far, numerical (J).
    pub bang_joints_j: f64,
    /// Final bang: kinetic energy the model discarded so far, joining the links into pieces
    /// at the release and freezing pieces at rest (J).
    pub bang_freeze_j: f64,
    /// Final bang: dissipated but not explained by the parts above, numerical (J).
    pub bang_residual_j: f64,
    /// Eq. (7): coil radius at this time (m).
    pub r_ref_m: f64,
    /// Eq. (7): contact position (m).
    pub x_ref_m: f64,
    /// Eq. (7): contact-line speed (m/s).
    pub xdot_ref_m_s: f64,
    /// Eq. (7): kinetic energy (J).
    pub kinetic_ref_j: f64,
    /// Eq. (9), exact form (ERRATA A4): floor normal force on the coil (N).
    pub normal_ref_n: f64,
    /// Eq. (11): horizontal force on the coil (N).
    pub friction_ref_n: f64,
    /// Exact-geometry model: equivalent radius (m).
    pub r_geo_m: f64,
    /// Exact-geometry model: contact position (m).
    pub x_geo_m: f64,
    /// Exact-geometry model: contact-line speed (m/s).
    pub xdot_geo_m_s: f64,
    /// Exact-geometry model: kinetic energy (J).
    pub kinetic_geo_j: f64,
    /// Eq. (17): coil radius (m).
    pub r_ft_m: f64,
    /// The scene's valid reference (see `rivals`): laid fraction at this time, `NaN` where
    /// it has none or past its end.
    pub laid_fraction_ref: f64,
    /// Spools: angle unrolled, `theta = f l / r` (rad); `NaN` for a solid coil.
    pub theta_rad: f64,
    /// Spools: the valid reference's `theta` at this time (rad).
    pub theta_ref_rad: f64,
    /// Total upward force on the moving part (the coil and the link hanging from it), from
    /// its momentum balance summed over the sample interval, `dP_y/dt + m g cos(a)` (N);
    /// `NaN` once the coil is released.
    pub n_tot_n: f64,
    /// Total horizontal force on the moving part, `dP_x/dt - m g sin(a)`, +x positive (N).
    pub f_tot_n: f64,
    /// The floor's upward force on the coil, its contact impulses over the interval (N).
    pub n_floor_n: f64,
    /// The floor's horizontal force on the coil, `F` of sec. 2.2, +x positive (N).
    pub f_floor_n: f64,
    /// The laid tape's upward force on the moving part, through its end: `n_tot - n_floor`
    /// (N).
    pub n_int_n: f64,
    /// The laid tape's horizontal force on the moving part, `F_int` of sec. 2.2:
    /// `f_tot - f_floor` (N).
    pub f_int_n: f64,
    /// Exact-geometry model at the simulation's laid fraction: `N_tot` from the momentum of
    /// the rolling spiral (N).
    pub n_tot_geo_n: f64,
    /// Exact-geometry model: `F_tot` from the momentum of the rolling spiral (N).
    pub f_tot_geo_n: f64,
    /// Exact-geometry model: the floor's horizontal force on the spiral, `F` (N).
    pub f_floor_geo_n: f64,
    /// Exact-geometry model: the laid tape's horizontal force on the spiral, `F_int` (N).
    pub f_int_geo_n: f64,
    /// Angular momentum of the moving part about the origin (the laid tape's outer end, on
    /// the contact plane) over the last step, from how far it moved, counter-clockwise
    /// (kg m^2/s).
    pub l_o: f64,
    /// Eq. (14) at the simulation's r and r' (from x' by constraint (1)): the coil as a disc
    /// (kg m^2/s).
    pub l_o_eq14: f64,
    /// The exact-geometry model's `L_O` at the simulation's laid fraction (kg m^2/s).
    pub l_o_geo: f64,
    /// Rate of change of the moving part's `L_O` over the force window, from the velocities
    /// the engine reports after each step (N m).
    pub dl_o_dt_n_m: f64,
    /// Torque about the origin of every external force on the moving part, gravity, the
    /// floor and the laid tape's pull, at the points where they act (N m).
    pub tau_o_n_m: f64,
    /// Eq. (16)'s placement of the same forces: gravity and the vertical forces at the
    /// contact line, the horizontal ones in the floor's plane (N m).
    pub tau_o_eq16_n_m: f64,
    /// What eq. (16) misses of gravity's torque: the spiral's centre of mass is not over the
    /// contact line (N m).
    pub tau_offcentre_n_m: f64,
    /// The case's analytic `N_tot` at the simulation's laid fraction (see `forces`) (N).
    pub n_tot_ref_n: f64,
    /// The case's analytic `F_tot` at the simulation's laid fraction (N).
    pub f_tot_ref_n: f64,
    /// Bodies in the engine.
    pub active_bodies: usize,
    /// Largest joint separation (m).
    pub max_joint_gap_m: f64,
    /// Deepest floor penetration (m).
    pub max_penetration_m: f64,
}

/// A sample's forces: the mean over its window (see
/// [`ForceWindow`](crate::run::force_window::ForceWindow)) of the floor's on
/// everything that moves always; while the coil rolls, those on the moving part, with the
/// references at the window's mean laid fraction.
pub(crate) fn set_forces(sample: &mut Sample, mean: &WindowMean, rolling: bool, refs: &References) {
    let f = &mean.forces;
    sample.normal_n = f.floor_on_moving[1];
    sample.friction_n = f.floor_on_moving[0];
    if !rolling {
        return;
    }
    let laid = f.laid();
    sample.n_tot_n = f.total[1];
    sample.f_tot_n = f.total[0];
    sample.n_floor_n = f.floor_on_coil[1];
    sample.f_floor_n = f.floor_on_coil[0];
    sample.n_int_n = laid[1];
    sample.f_int_n = laid[0];
    let a = &f.about_origin;
    sample.dl_o_dt_n_m = a.change;
    sample.tau_o_n_m = a.gravity + a.floor + a.laid;
    sample.tau_o_eq16_n_m = a.gravity_at_contact_line + a.others_at_contact_line;
    sample.tau_offcentre_n_m = a.gravity - a.gravity_at_contact_line;
    let nan = f64::NAN;
    let paper = refs.forces.as_ref().and_then(|r| r(mean.laid_fraction));
    sample.n_tot_ref_n = paper.map_or(nan, |p| p.0);
    sample.f_tot_ref_n = paper.map_or(nan, |p| p.1);
    let psi = refs.exact.psi_at_fraction(mean.laid_fraction);
    if let Some(geo) = refs.floor_grip.and_then(|mu| refs.exact.forces(psi, mu)) {
        sample.n_tot_geo_n = geo.n_tot_n;
        sample.f_tot_geo_n = geo.f_tot_n;
        sample.f_floor_geo_n = geo.f_floor_n;
        sample.f_int_geo_n = geo.f_int_n;
    }
}

/// Eq. (14), `L_O = M pi r^2 r' (R^2 + 2 r^2) / (b R^2)`, counter-clockwise, at the laid
/// fraction `f` and contact-line speed `x'`, with `r' = -b x' / (2 pi r)` from constraint
/// (1), `x = pi (R^2 - r^2) / b` (kg m^2/s).
fn eq14_angular_momentum(refs: &References, f: f64, xdot: f64) -> f64 {
    let p = refs.continuum.params();
    let (big_r, b, m) = (p.outer_radius_m, p.thickness_m, p.mass_kg);
    let r = big_r * (1.0 - f).max(0.0).sqrt();
    let rdot = -b * xdot / (2.0 * PI * r);
    m * PI * r * r * rdot * (big_r * big_r + 2.0 * r * r) / (b * big_r * big_r)
}

/// What a sample is made from: the step's observation, the contact line's speed, the energy
/// at the start and, for a sample with forces, its window's mean. Plain numbers, so an
/// observer on another thread can make the sample ([`Self::sample`]) with the references.
#[derive(Debug, Clone, Copy)]
pub struct SampleInputs {
    obs: Observation,
    xdot: f64,
    e0: f64,
    /// The forces' window mean, and whether the coil rolls.
    forces: Option<(WindowMean, bool)>,
}

impl SampleInputs {
    pub(crate) fn new(
        obs: &Observation,
        xdot: f64,
        e0: f64,
        forces: Option<(WindowMean, bool)>,
    ) -> Self {
        Self {
            obs: *obs,
            xdot,
            e0,
            forces,
        }
    }

    /// The sample, beside the references `refs`.
    pub fn sample(&self, refs: &References) -> Sample {
        let mut sample = make_sample(&self.obs, self.xdot, self.e0, refs);
        if let Some((mean, rolling)) = &self.forces {
            set_forces(&mut sample, mean, *rolling, refs);
        }
        sample
    }
}

pub(crate) fn make_sample(obs: &Observation, xdot: f64, e0: f64, refs: &References) -> Sample {
    let nan = f64::NAN;
    let c = refs.continuum.state_at_time(obs.t_s);
    let g = refs.exact.state_at_time(obs.t_s);
    let r_ref = c.map_or(nan, |s| s.r_m);
    let f_ref = refs
        .valid()
        .and_then(|r| r.fraction_at_time(obs.t_s))
        .unwrap_or(nan);
    let forces = refs.forces.as_ref().and_then(|f| f(obs.laid_fraction));
    let rolling = obs.phase == Phase::Rolling;
    let l_o_eq14 = match (rolling, refs.theta_per_fraction) {
        (true, None) => eq14_angular_momentum(refs, obs.laid_fraction, xdot),
        _ => nan,
    };
    Sample {
        t_s: obs.t_s,
        laid_fraction: obs.laid_fraction,
        r_m: (1.0 - obs.laid_fraction).max(0.0).sqrt() * refs.continuum.outer_radius_m(),
        x_m: obs.x_m,
        xdot_m_s: xdot,
        omega_rad_s: obs.omega_rad_s,
        kinetic_j: obs.kinetic_j,
        potential_j: obs.potential_j,
        dissipated_j: e0 - obs.kinetic_j - obs.potential_j,
        normal_n: obs.normal_n,
        friction_n: obs.friction_n,
        lost_step_j: obs.ledger.step_j,
        lost_detach_j: obs.ledger.detach_j,
        lost_freeze_j: obs.ledger.freeze_j,
        lost_bang_j: obs.ledger.bang_j,
        bang_floor_normal_j: obs.bang.ledger.floor_normal_j,
        bang_floor_friction_j: obs.bang.ledger.floor_friction_j,
        bang_layers_normal_j: obs.bang.ledger.layers_normal_j,
        bang_layers_friction_j: obs.bang.ledger.layers_friction_j,
        bang_joints_j: obs.bang.ledger.joints_j,
        bang_freeze_j: obs.bang.ledger.freeze_j,
        bang_residual_j: obs.bang.ledger.residual_j,
        r_ref_m: r_ref,
        x_ref_m: c.map_or(nan, |s| s.x_m),
        xdot_ref_m_s: c.map_or(nan, |s| s.xdot_m_s),
        kinetic_ref_j: c.map_or(nan, |s| s.kinetic_j),
        normal_ref_n: c.map_or(nan, |s| refs.continuum.normal_force_n(s.r_m)),
        friction_ref_n: c.map_or(nan, |s| refs.continuum.horizontal_force_n(s.r_m)),
        r_geo_m: g.map_or(nan, |s| s.r_m),
        x_geo_m: g.map_or(nan, |s| s.x_m),
        xdot_geo_m_s: g.map_or(nan, |s| s.xdot_m_s),
        kinetic_geo_j: g.map_or(nan, |s| s.kinetic_j),
        r_ft_m: refs.force_torque.radius_at_time(obs.t_s).unwrap_or(nan),
        laid_fraction_ref: f_ref,
        theta_rad: refs
            .theta_per_fraction
            .map_or(nan, |k| k * obs.laid_fraction),
        theta_ref_rad: refs.theta_per_fraction.map_or(nan, |k| k * f_ref),
        n_tot_n: nan,
        f_tot_n: nan,
        n_floor_n: nan,
        f_floor_n: nan,
        n_int_n: nan,
        f_int_n: nan,
        n_tot_geo_n: nan,
        f_tot_geo_n: nan,
        f_floor_geo_n: nan,
        f_int_geo_n: nan,
        l_o: if rolling { obs.angular_momentum_o } else { nan },
        l_o_eq14,
        l_o_geo: if rolling && refs.floor_grip.is_some() {
            refs.exact
                .angular_momentum_o(refs.exact.psi_at_fraction(obs.laid_fraction))
                .unwrap_or(nan)
        } else {
            nan
        },
        dl_o_dt_n_m: nan,
        tau_o_n_m: nan,
        tau_o_eq16_n_m: nan,
        tau_offcentre_n_m: nan,
        n_tot_ref_n: forces.map_or(nan, |f| f.0),
        f_tot_ref_n: forces.map_or(nan, |f| f.1),
        active_bodies: obs.active_bodies,
        max_joint_gap_m: obs.max_joint_gap_m,
        max_penetration_m: obs.max_penetration_m,
    }
}
