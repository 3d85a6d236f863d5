//! The nodal chain's step: Newton's method on the midpoint rule's equations, the floor's
//! contacts in the same iterations (their modes settled on each linearisation), each
//! iteration one banded solve (`system.rs`), a line search on a merit where the full step
//! would overshoot.

use super::system::{Assembly, Solution, solve, times_mass};
use super::{NodalChain, StepError, StepReport, add, contact, cross, dot, quarter, scale, sub};

/// The step's working memory, kept from step to step.
#[derive(Debug, Default)]
pub(in crate::model) struct Scratch {
    /// Nodes and velocities at the step's start; gravity's generalised impulse `h f`.
    pub(super) x0: Vec<[f64; 2]>,
    pub(super) v0: Vec<[f64; 2]>,
    pub(super) kick: Vec<[f64; 2]>,
    /// The step's length (s).
    pub(super) h: f64,
    /// Each piece's `c_i(x) / l_i` at the step's start (m).
    c0: Vec<f64>,
    /// The iterate: end velocities, rigidity impulses (N s).
    pub(super) v: Vec<[f64; 2]>,
    lambda: Vec<f64>,
    /// The contact points' data for the step, their modes and impulses.
    pub(super) contacts: contact::Contacts,
    pub(super) assembly: Assembly,
    pub(super) solution: Solution,
    /// The line search's iterate before the step, and the solve's impulses.
    trial: Vec<[f64; 2]>,
    trial_lambda: Vec<f64>,
    trial_impulses: Vec<[f64; 2]>,
    new_impulses: Vec<[f64; 2]>,
}

/// The step of [`NodalChain::step`], not halved.
pub(super) fn step(
    chain: &mut NodalChain,
    h: f64,
    gravity: [f64; 2],
) -> Result<StepReport, StepError> {
    let mut s = std::mem::take(&mut chain.scratch);
    let result = iterate(chain, &mut s, h, gravity);
    chain.scratch = s;
    result
}

fn iterate(
    chain: &mut NodalChain,
    s: &mut Scratch,
    h: f64,
    gravity: [f64; 2],
) -> Result<StepReport, StepError> {
    prepare(chain, s, h, gravity);
    let kinetic0 = chain.kinetic_j();
    if chain.pieces.is_empty() {
        return Ok(StepReport {
            converged: true,
            pieces: 1,
            ..StepReport::default()
        });
    }
    let tol = chain.position_tolerance_m();
    let mut report = StepReport {
        pieces: 1,
        ..StepReport::default()
    };
    // Iterations in a row whose line search took less than an eighth of Newton's step.
    let (mut stalled, mut outer) = (0, 0);
    // Whether the sliding points' friction may follow their normal impulse within the solve
    // (Newton's step on the bounds' fixed point), and whether the last linearisation's
    // modes held from its first pass.
    let (mut coupling, mut held) = (true, false);
    // The bounds' step towards the normal impulses, halved whenever their miss does not
    // shrink (friction lifting a point it then no longer holds, and so on).
    let (mut relax, mut last_miss) = (1.0, f64::INFINITY);
    while outer < chain.tolerance.max_iterations && stalled < STALLED {
        outer += 1;
        s.trial_impulses.clear();
        s.trial_impulses
            .extend(s.contacts.points.iter().map(|p| p.impulse));
        contact::couple(&mut s.contacts.points, coupling && held);
        let Some(passes) = settle_modes(chain, s, h, &mut report, &mut coupling)? else {
            return finish(chain, s, h, kinetic0, report);
        };
        let widest = s
            .solution
            .delta
            .iter()
            .fold(0.0_f64, |m, d| m.max(d[0].abs().max(d[1].abs())));
        if !(widest.is_finite() && s.solution.lambda.iter().all(|x| x.is_finite())) {
            return Err(StepError::NonFinite);
        }
        held = passes == 1;
        let (t, phi) = line_search(chain, s, h);
        stalled = if t < 0.125 { stalled + 1 } else { 0 };
        // Coupled friction whose Newton step had to be cut (high friction's near-singular
        // response): the bounds alone from now on.
        if t < 1.0 && contact::couple(&mut s.contacts.points, false) {
            coupling = false;
        }
        let gap = length_errors(chain, s, h);
        let bounds_moved = contact::update_bounds(chain, &mut s.contacts.points, relax);
        if bounds_moved >= last_miss {
            relax = (0.5 * relax).max(1.0 / 64.0);
        }
        last_miss = bounds_moved;
        // Newton's whole step within the tolerance (the iterate is that close to the
        // solution of its own linearisation, whose modes the passes settled), and the
        // friction bounds where the normal impulses put them.
        // Or, where the floor touches, the iterate's every residual within a hundredth of
        // the tolerance already: a step that moves along a direction they hardly see (a
        // point's impulse shared among redundant rows) changes nothing that matters.
        let settled = contact::any_touching(&s.contacts.points) && phi <= 1e-4 * tol * tol;
        let small = h * widest <= tol || settled;
        if gap <= tol && small && bounds_moved <= BOUND_TOLERANCE {
            report.converged = true;
            break;
        }
    }
    finish(chain, s, h, kinetic0, report)
}

/// Settles the contacts' modes on the iterate's linearisation, the friction bounds fixed:
/// each pass one solve, every broken mode changed while fewer break, then one at a time.
/// Returns the passes taken, or `None` if the modes did not settle within [`MAX_PASSES`].
/// A singular system with coupled friction (high friction's indeterminacy) turns the
/// coupling off for the rest of the step (`coupling`).
fn settle_modes(
    chain: &mut NodalChain,
    s: &mut Scratch,
    h: f64,
    report: &mut StepReport,
    coupling: &mut bool,
) -> Result<Option<u32>, StepError> {
    let tol_speed = chain.position_tolerance_m() / h;
    let (mut passes, mut fewest, mut stale) = (0, usize::MAX, 0);
    loop {
        report.iterations += 1;
        passes += 1;
        assemble_step(chain, s, h);
        let solved = solve(
            &chain.pieces,
            chain.pinned,
            &mut chain.system,
            &s.assembly,
            &mut s.solution,
        );
        if solved.is_err() && contact::couple(&mut s.contacts.points, false) {
            *coupling = false;
            continue;
        }
        solved?;
        s.trial.clear();
        s.trial
            .extend(s.v.iter().zip(&s.solution.delta).map(|(v, d)| add(*v, *d)));
        contact::take_impulses(
            &mut s.contacts.points,
            &s.solution.contact,
            contact::friction(chain),
        );
        let single = stale >= STALE_PASSES;
        let broken = contact::select(chain, &mut s.contacts.points, &s.trial, tol_speed, single);
        if broken == 0 {
            return Ok(Some(passes));
        }
        contact::couple(&mut s.contacts.points, false);
        if broken < fewest {
            (fewest, stale) = (broken, 0);
        } else {
            stale += 1;
        }
        if passes >= MAX_PASSES {
            return Ok(None);
        }
    }
}

/// Iterations in a row whose line search cuts Newton's step below an eighth before the step
/// is given up as stalled (and taken again in halves): the merit then sits in a valley that
/// holds no solution. On a flexing chain at 0.6 rad a step, an iteration that converges
/// does so in 3 to 7 iterations.
const STALLED: u32 = 4;

/// Block-pivoting passes that may go without fewer modes broken before the modes change
/// one at a time.
const STALE_PASSES: u32 = 3;

/// The most solves one linearisation's contact modes may take to settle before the step is
/// given up (and taken again in halves).
const MAX_PASSES: u32 = 60;

/// How far the friction bounds may be from `mu` times the normal impulses, relative to the
/// largest normal impulse, when the step converges: Coulomb's law holds to that fraction.
const BOUND_TOLERANCE: f64 = 1e-6;

/// Takes the solve's step from the iterate (its velocities, rigidity impulses and the
/// contacts' impulses before this linearisation, `s.trial_impulses`), shortened by halves
/// (down to 1/64) until it lowers the merit ([`merit`], with the settled modes) by at least
/// 1e-4 of its share: far from the solution (a piece turning half a radian a step) the full
/// Newton step can overshoot and cycle. A merit within a quarter of the position tolerance
/// squared is rounding, and takes the full step. Returns the fraction taken and the merit
/// before the step.
fn line_search(chain: &NodalChain, s: &mut Scratch, h: f64) -> (f64, f64) {
    s.new_impulses.clear();
    s.new_impulses
        .extend(s.contacts.points.iter().map(|p| p.impulse));
    for (p, old) in s.contacts.points.iter_mut().zip(&s.trial_impulses) {
        p.impulse = *old;
    }
    let phi = merit(chain, s, h);
    // Within the tolerance already, the merit is rounding: the full step is taken.
    let floor = 0.25 * chain.position_tolerance_m().powi(2);
    s.trial.clone_from(&s.v);
    s.trial_lambda.clone_from(&s.lambda);
    let mut t = 1.0;
    loop {
        for ((v, old), d) in s.v.iter_mut().zip(&s.trial).zip(&s.solution.delta) {
            *v = add(*old, scale(t, *d));
        }
        for ((l, old), new) in s
            .lambda
            .iter_mut()
            .zip(&s.trial_lambda)
            .zip(&s.solution.lambda)
        {
            *l = old + t * (new - old);
        }
        for ((p, old), new) in s
            .contacts
            .points
            .iter_mut()
            .zip(&s.trial_impulses)
            .zip(&s.new_impulses)
        {
            p.impulse = [0, 1].map(|k| old[k] + t * (new[k] - old[k]));
        }
        if phi <= floor {
            return (t, phi);
        }
        let trial = merit(chain, s, h);
        if t <= 1.0 / 64.0 || trial <= (1.0 - 1e-4 * t) * phi {
            return (t, trial);
        }
        t *= 0.5;
    }
}

/// How far the iterate is from solving the step: each piece's length error, each free
/// node's momentum residual times `h` over its mass, and each contact row's miss times `h`,
/// all lengths, squared and summed (m^2).
fn merit(chain: &NodalChain, s: &mut Scratch, h: f64) -> f64 {
    let mut r = times_mass(&chain.pieces, &s.v);
    let start = times_mass(&chain.pieces, &s.v0);
    let mut mass = vec![0.0; r.len()];
    for (k, x) in r.iter_mut().enumerate() {
        *x = sub(*x, add(start[k], s.kick[k]));
    }
    let mut phi = 0.0;
    for (i, p) in chain.pieces.iter().enumerate() {
        let (mid, end) = chord_ends(s, i, h);
        let l = p.length_m;
        let pull = scale(s.lambda[i] / l, mid);
        r[i] = add(r[i], pull);
        r[i + 1] = sub(r[i + 1], pull);
        let [a, b, _, _] = p.mass_blocks();
        mass[i] += a;
        mass[i + 1] += b;
        phi += (0.5 * (dot(end, end) - l * l) / l).powi(2);
    }
    contact::subtract_forces(chain, &s.contacts.points, &mut r);
    phi += h * h * contact::row_residuals(chain, &s.contacts.points, &s.v);
    let first = usize::from(chain.pinned);
    for k in first..r.len() {
        phi += (h / mass[k]).powi(2) * dot(r[k], r[k]);
    }
    phi
}

/// The step's start: nodes, velocities, gravity's kick, the rigidity's values, the first
/// iterate (the start's velocities, last step's tension), the contacts' targets.
fn prepare(chain: &NodalChain, s: &mut Scratch, h: f64, gravity: [f64; 2]) {
    s.h = h;
    s.x0.clone_from(&chain.nodes);
    s.v0.clone_from(&chain.velocities);
    s.v.clone_from(&chain.velocities);
    s.kick.clear();
    s.kick.resize(chain.nodes.len(), [0.0; 2]);
    s.c0.clear();
    s.lambda.clear();
    for (i, p) in chain.pieces.iter().enumerate() {
        let m = p.mass_kg;
        let [alpha, beta] = p.centre;
        let (g, jg) = (gravity, quarter(gravity));
        let near = add(scale(m * (1.0 - alpha), g), scale(m * beta, jg));
        let far = sub(scale(m * alpha, g), scale(m * beta, jg));
        s.kick[i] = add(s.kick[i], scale(h, near));
        s.kick[i + 1] = add(s.kick[i + 1], scale(h, far));
        let d = sub(s.x0[i + 1], s.x0[i]);
        s.c0.push(0.5 * (dot(d, d) - p.length_m * p.length_m) / p.length_m);
        s.lambda.push(chain.tension[i] * h);
    }
    predict(chain, s, h);
    contact::prepare(chain, &mut s.contacts.points, h);
}

/// The first iterate's end velocities: each piece turned rigidly at its spin as the midpoint
/// rule turns a free rotor (by `2 atan(omega h / 2)`), the nodes laid from node 0 (moved by
/// its velocity) along the turned chords. The pieces' lengths then hold from the start,
/// where the start's velocities would open them by `(omega h)^2 l / 2`.
fn predict(chain: &NodalChain, s: &mut Scratch, h: f64) {
    let mut end = add(s.x0[0], scale(h, s.v0[0]));
    s.v[0] = s.v0[0];
    for i in 0..chain.pieces.len() {
        let d = sub(s.x0[i + 1], s.x0[i]);
        let spin = cross(d, sub(s.v0[i + 1], s.v0[i])) / dot(d, d);
        let (sin, cos) = (2.0 * (0.5 * spin * h).atan()).sin_cos();
        let turned = [cos * d[0] - sin * d[1], sin * d[0] + cos * d[1]];
        end = add(end, turned);
        // x+ = x + h (v + v+) / 2.
        s.v[i + 1] = sub(scale(2.0 / h, sub(end, s.x0[i + 1])), s.v0[i + 1]);
    }
}

/// The linearised midpoint equations at the iterate, with the contacts' rows of their
/// modes.
fn assemble_step(chain: &NodalChain, s: &mut Scratch, h: f64) {
    let mut a = std::mem::take(&mut s.assembly);
    a.clear(true, chain.pieces.len());
    let touching = contact::any_touching(&s.contacts.points);
    for (i, p) in chain.pieces.iter().enumerate() {
        let l = p.length_m;
        let (mid, end) = chord_ends(s, i, h);
        // The rigidity's curvature (Newton's exact step). Where the floor touches, only
        // where it stiffens the system (a piece in tension): in compression it softens it,
        // and could make the contacts' problem lose its convexity (a point's response to
        // its own impulse turned against it); there the iterations go on without it
        // (Newton's chord, slower, to the same solution).
        let soft = 0.25 * h * s.lambda[i] / l;
        a.soft[i] = if touching { soft.min(0.0) } else { soft };
        a.col.push(scale(1.0 / l, mid));
        a.row.push(scale(1.0 / l, end));
        a.chord_rhs.push(-(dot(end, end) - l * l) / (h * l));
    }
    let momentum = times_mass(&chain.pieces, &s.v);
    let start = times_mass(&chain.pieces, &s.v0);
    for k in 0..chain.nodes.len() {
        let r = sub(add(start[k], s.kick[k]), momentum[k]);
        a.node_rhs.push(r);
    }
    contact::rows(
        chain,
        &mut s.contacts.points,
        &s.v,
        &mut a.contacts,
        &mut a.node_rhs,
    );
    s.assembly = a;
}

/// Piece `i`'s chord at the iterate's midpoint and end.
fn chord_ends(s: &Scratch, i: usize, h: f64) -> ([f64; 2], [f64; 2]) {
    let d0 = sub(s.x0[i + 1], s.x0[i]);
    let mean = |k: usize| scale(0.5, add(s.v0[k], s.v[k]));
    let dv = sub(mean(i + 1), mean(i));
    (add(d0, scale(0.5 * h, dv)), add(d0, scale(h, dv)))
}

/// The largest error of a piece's length at the iterate's end (m).
fn length_errors(chain: &NodalChain, s: &Scratch, h: f64) -> f64 {
    chain
        .pieces
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let (_, end) = chord_ends(s, i, h);
            (end[0].hypot(end[1]) - p.length_m).abs()
        })
        .fold(0.0, f64::max)
}

/// Ends the step: the nodes moved, the velocities set, the contacts recorded with their
/// work, the points below the floor moved out, the report filled in.
fn finish(
    chain: &mut NodalChain,
    s: &mut Scratch,
    h: f64,
    kinetic0: f64,
    mut report: StepReport,
) -> Result<StepReport, StepError> {
    for (k, x) in chain.nodes.iter_mut().enumerate() {
        let mean = scale(0.5, add(s.v0[k], s.v[k]));
        *x = add(s.x0[k], scale(h, mean));
    }
    chain.velocities.clone_from(&s.v);
    report.gravity_work_j = s
        .kick
        .iter()
        .zip(chain.nodes.iter().zip(&s.x0))
        .map(|(f, (x, x0))| dot(*f, sub(*x, *x0)) / h)
        .sum();
    for (i, p) in chain.pieces.iter().enumerate() {
        let d = sub(chain.nodes[i + 1], chain.nodes[i]);
        let c = 0.5 * (dot(d, d) - p.length_m * p.length_m) / p.length_m;
        report.joint_work_j += s.lambda[i] * (c - s.c0[i]) / h;
        let d0 = sub(s.x0[i + 1], s.x0[i]);
        report.max_turn_rad = report
            .max_turn_rad
            .max(cross(d0, d).atan2(dot(d0, d)).abs());
        chain.tension[i] = s.lambda[i] / h;
    }
    report.floor_work_j = contact::record(chain, &s.contacts.points, &s.x0, h);
    report.kinetic_change_j = chain.kinetic_j() - kinetic0;
    report.joint_gap_m = chain.length_error_m();
    // A projection that cannot meet every point's height is not kept (see
    // `contact::project_out`): the depth left is reported.
    let (projection_j, _) = contact::project_out(chain, &mut s.contacts, &s.kick, h)?;
    report.projection_j = projection_j;
    report.penetration_m = contact::penetration(chain, &s.contacts.points);
    Ok(report)
}
