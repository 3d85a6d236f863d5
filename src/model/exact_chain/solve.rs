//! One step of the exact chain, in RATTLE's three stages with the floor's impulses at the
//! step's start (see the parent's doc): the impulses at the start's pose, joints held; a
//! half kick of gravity and the drift, every joint closed at the step's end; a half kick of
//! gravity and the joints held at the end's pose.

use super::{ContactImpulse, ExactChain, StepError, StepReport, Surface};

mod active;
mod delassus;
mod dense;
mod layers;
mod modes;
mod project;
mod rows;

pub(super) use layers::{Key, LaidIndex};
pub(super) use modes::SLOP;
use modes::{Impulses, Source};
use project::{close_joints, project_out, realign};
use rows::{Pose, Row, Stage};

/// The step's working memory, kept from step to step.
#[derive(Debug, Default)]
pub(super) struct Scratch {
    /// The velocity at the step's start, `(u, w, omega)` per body.
    free: Vec<[f64; 3]>,
    /// Gravity (m/s^2) and the step's length (s).
    gravity: [f64; 2],
    /// The velocity gravity's half kick gives each body with the joints held, `(u, w,
    /// omega)`: what a contact's target before the drift meets ([`modes`]).
    fall: Vec<[f64; 3]>,
    h: f64,
    /// What the rows' impulses add to: the stage's starting velocity (for the impulses, with
    /// the sliding contacts' friction).
    base: Vec<[f64; 3]>,
    /// The iterate's velocity.
    v: Vec<[f64; 3]>,
    /// The stage's velocity with the joints held and no contact: the contacts' impulses act
    /// from it.
    held: Vec<[f64; 3]>,
    /// The velocity after the impulses at the start, and over the drift.
    after_impulses: Vec<[f64; 3]>,
    drift: Vec<[f64; 3]>,
    inv: Vec<[f64; 3]>,
    /// The pose at the step's start (the end's, for the last stage), and the drift's
    /// predicted end.
    start_pose: Pose,
    end_pose: Pose,
    candidates: Vec<modes::Candidate>,
    /// The layers' features the step measures ([`layers::near`]), and each body's margin
    /// they were found within (m).
    near: Vec<Key>,
    near_margin: Vec<f64>,
    /// Each time `near` was found.
    near_generation: u64,
    /// The layers' touches of `near` at `start_pose` ([`modes::measure`]), and the
    /// generations of the two they were measured at.
    touches: Vec<layers::Touch>,
    measured: Option<(u64, u64)>,
    rows: Vec<Row>,
    /// Where [`rows::build`]'s extra rows went among `rows`.
    extra_at: Vec<usize>,
    sizes: Vec<usize>,
    x: Vec<f64>,
    /// The bodies before the step, to restore on a failure.
    saved: Vec<super::Body>,
    /// Each contact point's height above the floor at the step's start (m).
    start_gaps: Vec<f64>,
    /// The layers' touches that overlap at the step's start, and by how much (m, negative),
    /// by key: the depth a step may leave them at.
    layer_start_gaps: Vec<(Key, f64)>,
    /// Where `ExactChain::system` holds the factorisation of the joints held with no
    /// contact ([`rows::solve_held`]), each body's position, angle, mass and inertia it was
    /// made at; empty where it holds another.
    held_key: Vec<[f64; 5]>,
}

/// The step of [`ExactChain::step`]. Where `may_halve`, a step whose drift fails (it does
/// not close the joints, or turns a body further than [`super::Tolerance::max_turn_rad`])
/// ends there, unfinished: the caller takes it again in halves, and its end would be
/// solved for nothing.
pub(super) fn step(
    chain: &mut ExactChain,
    h: f64,
    gravity: [f64; 2],
    may_halve: bool,
) -> Result<StepReport, StepError> {
    let mut s = std::mem::take(&mut chain.scratch);
    s.saved.clone_from(&chain.bodies);
    let result = stages(chain, &mut s, h, gravity, may_halve);
    if result.is_err() {
        chain.bodies.clone_from(&s.saved);
    }
    chain.scratch = s;
    result
}

fn stages(
    chain: &mut ExactChain,
    s: &mut Scratch,
    h: f64,
    gravity: [f64; 2],
    may_halve: bool,
) -> Result<StepReport, StepError> {
    s.h = h;
    if chain.bounded {
        close_joints(chain, s)?;
    }
    prepare(chain, s, gravity)?;
    chain.contacts.clear();
    held_fall(chain, s, h)?;
    modes::gather(chain, s, Impulses::Start(h));
    let mut report = if chain.fresh || !s.candidates.is_empty() {
        impulses(chain, s, Impulses::Start(h))?
    } else {
        s.v.clone_from(&s.free);
        StepReport {
            converged: true,
            ..StepReport::default()
        }
    };
    let start_floor = record_contacts(chain, s);
    report.joint_work_j[0] = kinetic(chain, &s.v) - kinetic(chain, &s.free) - start_floor;
    if chain.fresh {
        report.caught_j = -report.joint_work_j[0];
    }
    s.after_impulses.clone_from(&s.v);
    let (iterations, closed) = drift(chain, s, h, gravity, may_halve)?;
    report.iterations += iterations;
    report.converged &= closed;
    report.drift_closed = closed;
    report.pieces = 1;
    report.max_turn_rad = s.drift.iter().map(|v| (h * v[2]).abs()).fold(0.0, f64::max);
    if may_halve && !chain.drift_holds(&report) {
        return Ok(report);
    }
    // Move to the end, then the second half kick, and the impulses there.
    for (b, v) in chain.bodies.iter_mut().zip(&s.drift) {
        b.position_m = [b.position_m[0] + h * v[0], b.position_m[1] + h * v[1]];
        b.angle_rad += h * v[2];
    }
    s.start_pose.take(chain, None);
    let (closed, moved) = project_out(chain, s)?;
    report.converged &= closed;
    report.joint_gap_m = s.start_pose.joint_gap(chain);
    s.free = kicked(&s.drift, gravity, 0.5 * h);
    let [first_kick, mut second_kick] = gravity_work(chain, s, h, gravity);
    report.joint_work_j[1] =
        kinetic(chain, &s.drift) - kinetic(chain, &s.after_impulses) - first_kick;
    if moved && chain.bounded {
        report.projection_j = realign(chain, s, gravity, h)?;
        report.joint_work_j[1] += report.projection_j;
        second_kick = gravity_work(chain, s, h, gravity)[1];
    }
    report.gravity_work_j = first_kick + second_kick;
    modes::gather(chain, s, Impulses::End);
    let end = impulses(chain, s, Impulses::End)?;
    report.iterations += end.iterations;
    report.converged &= end.converged;
    let end_floor = record_contacts(chain, s);
    report.joint_work_j[2] =
        kinetic(chain, &s.v) - kinetic(chain, &s.drift) - second_kick - end_floor;
    if !s.v.iter().flatten().all(|x| x.is_finite()) {
        return Err(StepError::NonFinite);
    }
    report.penetration_m = modes::penetration(chain, s);
    report.overlap_m = modes::overlap(chain, s);
    report.beyond_reach_m = modes::beyond_reach(chain, s);
    for (b, v) in chain.bodies.iter_mut().zip(&s.v) {
        b.velocity_m_s = [v[0], v[1]];
        b.spin_rad_s = v[2];
    }
    Ok(report)
}

/// The impulses of `stage` at the current pose on the velocity `s.free`, the joints held,
/// the contacts solved against them ([`delassus::solve`]), again with any point the result
/// would take below the floor that was not among the candidates. The velocity after them is
/// left in `s.v`.
fn impulses(
    chain: &mut ExactChain,
    s: &mut Scratch,
    stage: Impulses,
) -> Result<StepReport, StepError> {
    let mut report = StepReport::default();
    for _ in 0..4 {
        // Few contacts: the active set on their Delassus matrix where the tape has its
        // thickness (Gauss-Seidel converges slowly on tape piled on laid tape), else
        // Gauss-Seidel. Many: the active set in the joints' band, unless a contact joins
        // two bodies (the tape's layers), whose rows would break the band; then
        // Gauss-Seidel, as the dense active set's direct solves grow as the cube of the
        // contacts (on the frictionless coil, 300 contacts, 0.3 s a stage). Gauss-Seidel
        // wherever an active set's modes did not settle.
        let few = s.candidates.len() < active::FROM_CONTACTS;
        let pairs = s.candidates.iter().any(|c| c.other.is_some());
        let settled = if few && chain.layers.is_some() && !s.candidates.is_empty() {
            dense::solve(chain, s)?
        } else if !few && !pairs {
            active::solve(chain, s)?
        } else {
            None
        };
        let solved = match settled {
            Some(solved) => solved,
            None => delassus::solve(chain, s)?,
        };
        report.iterations += solved.iterations;
        report.converged = solved.converged;
        if !modes::reach_new_points(chain, s, stage)? {
            break;
        }
    }
    Ok(report)
}

/// Gravity's half kick over `h`, with the joints held, into `s.fall`: the velocity the
/// drift's first half kick adds across each contact. One more solve of the joints' system,
/// factorised at the start's pose as the impulses' own is (`rows::solve_held` keeps it).
fn held_fall(chain: &mut ExactChain, s: &mut Scratch, h: f64) -> Result<(), StepError> {
    let kick = [0.5 * h * s.gravity[0], 0.5 * h * s.gravity[1], 0.0];
    if chain.floor.is_some() || chain.layers.is_some() {
        let free = std::mem::replace(&mut s.free, vec![kick; chain.bodies.len()]);
        let held = delassus::hold(chain, s);
        s.free = free;
        held?;
        std::mem::swap(&mut s.fall, &mut s.v);
        s.v.clone_from(&s.free);
    } else {
        s.fall.clear();
        s.fall.resize(chain.bodies.len(), kick);
    }
    Ok(())
}

/// A chord iteration of the drift must shrink the widest gap at least this many times, or
/// the next iteration factorises the system again (a full Newton iteration).
const CHORD_CONTRACTION: f64 = 0.5;

/// The drift: a half kick of gravity, then every joint closed at the step's end by
/// impulses along the start's Jacobians (Newton's method on the gaps, SHAKE). The first
/// iteration factorises the Newton system at the predicted end; later ones reuse that
/// factorisation for the new gaps (the chord method: each a back-substitution, no
/// factorisation), and factorise again only where a chord iteration shrank the widest gap
/// by less than [`CHORD_CONTRACTION`]. The iterations converge to the same tolerance
/// either way. Where `may_halve`, the iterations stop, not closed, at an iterate whose
/// widest gap is wider than the first's: they are diverging (on the thin tape, 147 of the
/// 151 drifts that ran to the iteration cap without closing did so, most within 6
/// iterations, and no drift that closed ever did). Returns the iterations and whether the
/// gaps closed within the tolerance; the drift's velocity is left in `s.drift`. Where the
/// steps are bounded, each joint ends the drift with the gap it started the step with
/// (`rows::joint_opened`), closed by position instead (`project::close_joints`).
fn drift(
    chain: &mut ExactChain,
    s: &mut Scratch,
    h: f64,
    gravity: [f64; 2],
    may_halve: bool,
) -> Result<(u32, bool), StepError> {
    let tol = position_tolerance(chain);
    s.base = kicked(&s.after_impulses, gravity, 0.5 * h);
    s.v.clone_from(&s.base);
    let mut iterations = 0;
    let mut closed = chain.joints.is_empty() && chain.pin.is_none();
    // The widest gap when the system was last solved, and whether its factorisation holds.
    let (mut last_gap, mut factored) = (f64::INFINITY, false);
    let mut first_gap = None;
    while !closed && iterations < chain.tolerance.max_iterations {
        s.end_pose.take(chain, Some((&s.v, h)));
        let gap = rows::widest_opened(chain, s);
        if gap <= tol {
            closed = true;
            break;
        }
        if may_halve && gap > *first_gap.get_or_insert(gap) {
            break;
        }
        iterations += 1;
        if factored && gap <= CHORD_CONTRACTION * last_gap {
            rows::drift_gaps(chain, s, h);
            chain.system.solve(&mut s.x);
            rows::finite(s)?;
            rows::add_impulses(s);
        } else {
            rows::build(chain, s, Stage::Drift(h), &[]);
            rows::solve(chain, s)?;
            rows::apply(s);
            factored = true;
        }
        last_gap = gap;
    }
    s.drift.clone_from(&s.v);
    Ok((iterations, closed))
}

/// `v` with gravity's impulse over `dt` added.
fn kicked(v: &[[f64; 3]], gravity: [f64; 2], dt: f64) -> Vec<[f64; 3]> {
    v.iter()
        .map(|v| [v[0] + dt * gravity[0], v[1] + dt * gravity[1], v[2]])
        .collect()
}

/// Gravity's work in each half kick, its impulse times the mean velocity over it (J):
/// the first from the impulses' velocity to the drift's, the second from the drift's to
/// `s.free`.
fn gravity_work(chain: &ExactChain, s: &Scratch, h: f64, gravity: [f64; 2]) -> [f64; 2] {
    let mut work = [0.0; 2];
    for (i, b) in chain.bodies.iter().enumerate() {
        let (a, d, e) = (s.after_impulses[i], s.drift[i], s.free[i]);
        let mean = |p: [f64; 3], q: [f64; 3]| [0.5 * (p[0] + q[0]), 0.5 * (p[1] + q[1])];
        for (w, m) in work.iter_mut().zip([mean(a, d), mean(d, e)]) {
            *w += 0.5 * h * b.mass_kg * (gravity[0] * m[0] + gravity[1] * m[1]);
        }
    }
    work
}

/// The chain's kinetic energy at the velocities `v` (J).
fn kinetic(chain: &ExactChain, v: &[[f64; 3]]) -> f64 {
    chain
        .bodies
        .iter()
        .zip(v)
        .map(|(b, v)| {
            0.5 * b.mass_kg * (v[0] * v[0] + v[1] * v[1]) + 0.5 * b.inertia_kg_m2 * v[2] * v[2]
        })
        .sum()
}

/// The chain's position tolerance, no finer than 4096 roundings of its largest coordinate.
pub(super) fn position_tolerance(chain: &ExactChain) -> f64 {
    let largest = chain
        .bodies
        .iter()
        .flat_map(|b| b.position_m)
        .fold(0.0, |m: f64, x| m.max(x.abs()));
    chain
        .tolerance
        .position_m
        .max(4096.0 * f64::EPSILON * largest)
}

/// Each body's inverse mass matrix, `(1/m, 1/m, 1/I)`, into `s.inv`.
fn inverse_masses(chain: &ExactChain, s: &mut Scratch) {
    s.inv.clear();
    s.inv.extend(
        chain
            .bodies
            .iter()
            .map(|b| [1.0 / b.mass_kg, 1.0 / b.mass_kg, 1.0 / b.inertia_kg_m2]),
    );
}

/// The start's velocity and pose, and the inverse masses; the layers' features within
/// reach, which fails where their search outgrows its bound.
fn prepare(chain: &ExactChain, s: &mut Scratch, gravity: [f64; 2]) -> Result<(), StepError> {
    s.free.clear();
    for b in &chain.bodies {
        let [u, w] = b.velocity_m_s;
        s.free.push([u, w, b.spin_rad_s]);
    }
    inverse_masses(chain, s);
    s.v.clone_from(&s.free);
    s.gravity = gravity;
    s.start_pose.take(chain, None);
    s.start_gaps.clear();
    if let Some(floor) = chain.floor {
        let r = chain.radius_m();
        for i in 0..chain.bodies.len() {
            for &local in &chain.vertices[chain.vertex_at[i]..chain.vertex_at[i + 1]] {
                s.start_gaps
                    .push(floor.gap(s.start_pose.point(i, local)) - r);
            }
        }
    }
    s.layer_start_gaps.clear();
    if chain.layers.is_some() {
        let free = std::mem::take(&mut s.free);
        let found = modes::find_near(chain, s, s.h, &free);
        s.free = free;
        found?;
        modes::measure(chain, s);
        let touches = std::mem::take(&mut s.touches);
        s.layer_start_gaps.extend(
            touches
                .iter()
                .filter(|t| t.gap_m < 0.0)
                .map(|t| (t.key, t.gap_m)),
        );
        s.touches = touches;
    }
    Ok(())
}

/// Keeps the contacts' impulses of the stage just solved, their work, and their impulses as
/// the next stage's first guess. Returns their work (J). Each impulse's work is it times the
/// mean relative velocity of the points it acts between, from `s.held` (the joints held, no
/// contact) to `s.v`: both hold the joints, so the joints' impulses do no work between them
/// and the contacts' work is that step's whole change of kinetic energy, however the impulse
/// is shared among points that hold the same motion (several points of a piece flat on the
/// floor). What the joints take from `s.free` to `s.held` is theirs.
fn record_contacts(chain: &mut ExactChain, s: &Scratch) -> f64 {
    let mut total = 0.0;
    chain.warm.fill([0.0; 2]);
    chain.layer_warm.clear();
    for c in &s.candidates {
        match c.source {
            Source::Floor(v) => chain.warm[v] = [c.normal, c.tangent],
            Source::Layer(key) => chain.layer_warm.push((key, [c.normal, c.tangent])),
        }
        if c.normal == 0.0 && c.tangent == 0.0 {
            continue;
        }
        let (before, after) = (c.speeds(&s.held), c.speeds(&s.v));
        let mean = |k: usize| 0.5 * (before[k] + after[k]);
        let work_j = [c.normal * mean(0), c.tangent * mean(1)];
        total += work_j[0] + work_j[1];
        let (n, t) = (c.n, c.t());
        let on = modes::surface(c);
        chain.contacts.push(ContactImpulse {
            body: c.body,
            vertex: match c.source {
                Source::Floor(v) => v - chain.vertex_at[c.body],
                Source::Layer(_) => 0,
            },
            on,
            normal_n_s: [n[0] * c.normal, n[1] * c.normal],
            friction_n_s: [t[0] * c.tangent, t[1] * c.tangent],
            arm_m: c.arm,
            other_arm_m: if matches!(on, Surface::Body(_)) {
                c.arm_other
            } else {
                [0.0; 2]
            },
            work_j,
        });
    }
    chain.layer_warm.sort_by_key(|w| w.0);
    total
}
