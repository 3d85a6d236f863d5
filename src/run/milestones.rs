//! The milestones of a run: the laid fractions it is timed at (0.75R, 0.5R, 0.25R, 0.1R
//! and 2b; a spool at laid fractions), when the simulation crossed each, and the
//! references' times there.

use crate::model::{Observation, Phase};
use crate::run::report::{Milestone, MilestoneKey, RivalTimes};
use crate::scene::Scene;
use crate::theory::References;

/// Laid fractions of the milestones of a spool (a scene with a core).
pub const SPOOL_FRACTIONS: [f64; 4] = [0.25, 0.5, 0.75, 0.9];

/// The milestone radii of a scene with their keys.
pub fn milestone_radii(scene: &Scene) -> Vec<(MilestoneKey, f64)> {
    let big_r = scene.tape.outer_radius_m;
    if scene.tape.core_radius_m > 0.0 {
        // On a spool the radius hardly changes: milestones at laid fractions f, given as
        // the continuum-equivalent radius R sqrt(1 - f) the loop converts back.
        return SPOOL_FRACTIONS
            .iter()
            .map(|&f| (MilestoneKey::Laid(f), big_r * (1.0 - f).sqrt()))
            .collect();
    }
    let mut v: Vec<(MilestoneKey, f64)> = [0.75, 0.5, 0.25, 0.1]
        .iter()
        .map(|&k| (MilestoneKey::OfRadius(k), k * big_r))
        .collect();
    v.push((MilestoneKey::TwoB, 2.0 * scene.tape.thickness_m));
    v
}

/// Where the simulation stood when it crossed a milestone.
struct Hit {
    t_s: f64,
    xdot: f64,
    kinetic: f64,
    potential: f64,
    /// What the bang had dissipated by then (J), left out of the milestone's loss. A
    /// milestone crossed in the step that releases the coil (the thin tape's 2b, its release
    /// radius) takes the energies before that step, as the ledger's "before the bang" does.
    bang_j: f64,
}

/// The milestones of a scene and when the run crossed them.
pub(crate) struct Milestones {
    radii: Vec<(MilestoneKey, f64)>,
    fractions: Vec<f64>,
    hits: Vec<Option<Hit>>,
}

impl Milestones {
    pub(crate) fn new(scene: &Scene) -> Self {
        let radii = milestone_radii(scene);
        let big_r = scene.tape.outer_radius_m;
        let fractions = radii
            .iter()
            .map(|(_, r)| 1.0 - (r / big_r).powi(2))
            .collect();
        let hits = radii.iter().map(|_| None).collect();
        Self {
            radii,
            fractions,
            hits,
        }
    }

    /// Notes the milestones crossed between the steps `p` and `obs`, each at the time the
    /// laid fraction reached it (interpolated in the step).
    pub(crate) fn observe(&mut self, p: &Observation, obs: &Observation, xdot: f64) {
        for (k, &f) in self.fractions.iter().enumerate() {
            if self.hits[k].is_none() && p.laid_fraction < f && obs.laid_fraction >= f {
                let s = (f - p.laid_fraction) / (obs.laid_fraction - p.laid_fraction);
                // Crossed in the step that releases the coil: its energies before the
                // release, as the ledger's "before the bang" takes them.
                let at = if p.phase == Phase::Rolling && obs.phase != Phase::Rolling {
                    p
                } else {
                    obs
                };
                self.hits[k] = Some(Hit {
                    t_s: p.t_s + s * (obs.t_s - p.t_s),
                    xdot,
                    kinetic: at.kinetic_j,
                    potential: at.potential_j,
                    bang_j: at.ledger.bang_j,
                });
            }
        }
    }

    /// Each of the paper's rivals for the case, timed at the milestones' laid fractions.
    pub(crate) fn rivals(&self, refs: &References) -> Vec<RivalTimes> {
        refs.rivals
            .iter()
            .map(|r| RivalTimes {
                label: r.label.clone(),
                description: r.description.clone(),
                valid: r.valid,
                stall_fraction: r.stall_fraction,
                t_s: self
                    .fractions
                    .iter()
                    .map(|&f| r.time_at_fraction(f))
                    .collect(),
            })
            .collect()
    }

    /// Each milestone with the simulation's time beside the references'.
    pub(crate) fn finish(&self, refs: &References, e0: f64) -> Vec<Milestone> {
        self.radii
            .iter()
            .zip(self.fractions.iter())
            .zip(self.hits.iter())
            .map(|(((label, r), &f), hit)| {
                let t_geo = refs.exact.time_at_fraction(f);
                let t_eq7 = refs.continuum.time_at_radius(*r);
                let t_sim = hit.as_ref().map(|h| h.t_s);
                let rel = |a: Option<f64>, b: Option<f64>| a.zip(b).map(|(a, b)| a / b - 1.0);
                Milestone {
                    key: *label,
                    label: label.to_string(),
                    r_m: *r,
                    laid_fraction: f,
                    t_sim_s: t_sim,
                    t_geo_s: t_geo,
                    t_eq7_s: t_eq7,
                    t_eq17_s: Some(refs.force_torque.time_at_radius(*r)),
                    err_vs_geo: rel(t_sim, t_geo),
                    err_vs_eq7: rel(t_sim, t_eq7),
                    geo_vs_eq7: rel(t_geo, t_eq7),
                    xdot_sim_m_s: hit.as_ref().map(|h| h.xdot),
                    xdot_eq7_m_s: t_eq7.map(|_| refs.continuum.state_at_radius(*r, 0.0).xdot_m_s),
                    kinetic_j: hit.as_ref().map(|h| h.kinetic),
                    potential_j: hit.as_ref().map(|h| h.potential),
                    dissipated_j: hit
                        .as_ref()
                        .map(|h| e0 - h.kinetic - h.potential - h.bang_j),
                }
            })
            .collect()
    }
}
