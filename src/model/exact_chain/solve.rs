//! One step of the exact chain: the rows of its constraints at each Newton iterate, their
//! block-tridiagonal system, the contacts' modes, and the bodies moved at the end.

use super::blocks::Singular;
use super::{ContactImpulse, ExactChain, Mode, REGULARISATION, StepError, StepReport};

/// A friction impulse may exceed `mu p_n` by this fraction before the contact slides: the
/// solve's rounding, not a physical margin.
const CONE_SLACK: f64 = 1e-9;

/// One row of the constraints: its Jacobian `k` at the iterate's predicted pose (what it
/// holds) and its impulse's direction `d` at the step's start (where it pushes), on one or
/// two bodies, `k M^-1 d^T x = rhs`.
#[derive(Debug, Clone, Copy, Default)]
struct Row {
    body: [usize; 2],
    count: usize,
    k: [[f64; 3]; 2],
    d: [[f64; 3]; 2],
    rhs: f64,
    reg: f64,
}

/// A contact point within reach of the floor this step.
#[derive(Debug, Clone, Copy)]
struct Candidate {
    vertex: usize,
    body: usize,
    local: [f64; 2],
    /// Its offset from the centre of mass at the step's start (world, m).
    arm: [f64; 2],
    /// The gap it may not end below: 0, or its depth if it started below the floor (a
    /// penetration is not pushed out, which would add energy).
    floor_m: f64,
    mode: Mode,
    /// Its first row in the system while on the floor.
    row: usize,
    normal: f64,
    tangent: f64,
}

/// The step's working memory, kept from step to step.
#[derive(Debug, Default)]
pub(super) struct Scratch {
    /// Velocity after gravity alone, `(u, w, omega)` per body.
    free: Vec<[f64; 3]>,
    /// The iterate's velocity.
    v: Vec<[f64; 3]>,
    inv: Vec<[f64; 3]>,
    /// The predicted pose `q + h v`: centre, cosine and sine of the angle.
    centre: Vec<[f64; 2]>,
    turn: Vec<[f64; 2]>,
    candidates: Vec<Candidate>,
    rows: Vec<Row>,
    sizes: Vec<usize>,
    x: Vec<f64>,
}

/// The step of [`ExactChain::step`].
pub(super) fn step(
    chain: &mut ExactChain,
    h: f64,
    gravity: [f64; 2],
) -> Result<StepReport, StepError> {
    let mut s = std::mem::take(&mut chain.scratch);
    let result = solve(chain, &mut s, h, gravity);
    if result.is_ok() {
        finish(chain, &s, h);
    }
    chain.scratch = s;
    result
}

fn solve(
    chain: &mut ExactChain,
    s: &mut Scratch,
    h: f64,
    gravity: [f64; 2],
) -> Result<StepReport, StepError> {
    prepare(chain, s, h, gravity);
    let tol = chain.tolerance.position_m;
    let mut report = StepReport::default();
    for iteration in 1..=chain.tolerance.max_iterations {
        report.iterations = iteration;
        predict(chain, s, h);
        build_rows(chain, s, h);
        solve_rows(chain, s)?;
        apply(s);
        predict(chain, s, h);
        let (changed, gaps) = settle_modes(chain, s, h);
        let joint_gap = joint_gap(chain, s);
        report.joint_gap_m = joint_gap;
        if !changed && joint_gap <= tol && gaps <= tol && !reach_new_points(chain, s) {
            report.converged = true;
            break;
        }
    }
    report.penetration_m = s
        .candidates
        .iter()
        .map(|c| {
            let floor = chain.floor.expect("candidates need a floor");
            -floor.gap(predicted_point(s, c.body, c.local))
        })
        .fold(0.0, f64::max);
    let finite = s.v.iter().flatten().all(|x| x.is_finite());
    if finite {
        Ok(report)
    } else {
        Err(StepError::NonFinite)
    }
}

/// Gravity's velocity, the inverse masses, the first iterate (the start's velocity) and
/// the contact points within reach of the floor this step.
fn prepare(chain: &ExactChain, s: &mut Scratch, h: f64, gravity: [f64; 2]) {
    s.free.clear();
    s.v.clear();
    s.inv.clear();
    for b in &chain.bodies {
        let [u, w] = b.velocity_m_s;
        s.free
            .push([u + h * gravity[0], w + h * gravity[1], b.spin_rad_s]);
        s.v.push([u, w, b.spin_rad_s]);
        s.inv
            .push([1.0 / b.mass_kg, 1.0 / b.mass_kg, 1.0 / b.inertia_kg_m2]);
    }
    s.candidates.clear();
    let Some(floor) = chain.floor else { return };
    let g = gravity[0].hypot(gravity[1]);
    for (i, b) in chain.bodies.iter().enumerate() {
        for vertex in chain.vertex_at[i]..chain.vertex_at[i + 1] {
            let local = chain.vertices[vertex];
            let arm = b.arm(local);
            let gap = floor.gap(b.point(local));
            let [u, w] = b.velocity_at(arm);
            // Within reach: twice as far as the point would go at its speed, or under
            // gravity alone.
            let reach = 2.0 * h * (u.hypot(w) + g * h) + chain.tolerance.position_m;
            if gap < reach {
                s.candidates
                    .push(candidate(chain, vertex, i, local, arm, gap));
            }
        }
    }
}

fn candidate(
    chain: &ExactChain,
    vertex: usize,
    body: usize,
    local: [f64; 2],
    arm: [f64; 2],
    gap: f64,
) -> Candidate {
    Candidate {
        vertex,
        body,
        local,
        arm,
        floor_m: gap.min(0.0),
        mode: chain.modes[vertex],
        row: 0,
        normal: 0.0,
        tangent: 0.0,
    }
}

/// The predicted pose `q + h v` of every body at the current iterate.
fn predict(chain: &ExactChain, s: &mut Scratch, h: f64) {
    s.centre.clear();
    s.turn.clear();
    for (b, v) in chain.bodies.iter().zip(&s.v) {
        s.centre
            .push([b.position_m[0] + h * v[0], b.position_m[1] + h * v[1]]);
        let (sin, cos) = (b.angle_rad + h * v[2]).sin_cos();
        s.turn.push([cos, sin]);
    }
}

fn predicted_arm(s: &Scratch, body: usize, local: [f64; 2]) -> [f64; 2] {
    let [c, sn] = s.turn[body];
    [c * local[0] - sn * local[1], sn * local[0] + c * local[1]]
}

fn predicted_point(s: &Scratch, body: usize, local: [f64; 2]) -> [f64; 2] {
    let a = predicted_arm(s, body, local);
    [s.centre[body][0] + a[0], s.centre[body][1] + a[1]]
}

/// The Jacobian of the world point at offset `arm` along the world direction `dir`, per
/// unit of `(u, w, omega)`.
fn along(dir: [f64; 2], arm: [f64; 2]) -> [f64; 3] {
    [dir[0], dir[1], arm[0] * dir[1] - arm[1] * dir[0]]
}

fn dot3(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn weighted(a: [f64; 3], w: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * w[0] * b[0] + a[1] * w[1] * b[1] + a[2] * w[2] * b[2]
}

/// A row on one body, or two (`second`), with `rhs` still to be completed by the iterate.
fn row(body: usize, k: [f64; 3], d: [f64; 3], second: Option<(usize, [f64; 3], [f64; 3])>) -> Row {
    let mut r = Row {
        body: [body, 0],
        count: 1,
        k: [k, [0.0; 3]],
        d: [d, [0.0; 3]],
        rhs: 0.0,
        reg: 0.0,
    };
    if let Some((b, k2, d2)) = second {
        r.body[1] = b;
        r.count = 2;
        r.k[1] = k2;
        r.d[1] = d2;
    }
    r
}

/// The rows of the constraints at the current iterate, block by block: body `i`'s block
/// holds the pin's rows (body 0), its contacts' rows and the joint to body `i + 1`.
fn build_rows(chain: &ExactChain, s: &mut Scratch, h: f64) {
    s.rows.clear();
    s.sizes.clear();
    let mut next_candidate = 0;
    for i in 0..chain.bodies.len() {
        let start = s.rows.len();
        if i == 0
            && let Some(pin) = chain.pin
        {
            let (a0, a1) = (
                chain.bodies[0].arm(pin.anchor),
                predicted_arm(s, 0, pin.anchor),
            );
            let p = predicted_point(s, 0, pin.anchor);
            for (c, dir) in [[1.0, 0.0], [0.0, 1.0]].into_iter().enumerate() {
                let mut r = row(0, along(dir, a1), along(dir, a0), None);
                r.rhs = dot3(r.k[0], sub3(s.v[0], s.free[0])) - (p[c] - pin.at_m[c]) / h;
                s.rows.push(r);
            }
        }
        while next_candidate < s.candidates.len() && s.candidates[next_candidate].body == i {
            contact_rows(chain, s, next_candidate, h);
            next_candidate += 1;
        }
        if i + 1 < chain.bodies.len() {
            joint_rows(chain, s, i, h);
        }
        s.sizes.push(s.rows.len() - start);
    }
    while s.sizes.last() == Some(&0) {
        s.sizes.pop();
    }
}

fn sub3(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// Joint `i`'s two rows: the gap between body `i`'s anchor and body `i + 1`'s.
fn joint_rows(chain: &ExactChain, s: &mut Scratch, i: usize, h: f64) {
    let j = chain.joints[i];
    let (a0, b0) = (chain.bodies[i].arm(j.prev), chain.bodies[i + 1].arm(j.next));
    let (a1, b1) = (predicted_arm(s, i, j.prev), predicted_arm(s, i + 1, j.next));
    let (pa, pb) = (
        predicted_point(s, i, j.prev),
        predicted_point(s, i + 1, j.next),
    );
    for (c, dir) in [[1.0, 0.0], [0.0, 1.0]].into_iter().enumerate() {
        let neg = [-dir[0], -dir[1]];
        let mut r = row(
            i,
            along(dir, a1),
            along(dir, a0),
            Some((i + 1, along(neg, b1), along(neg, b0))),
        );
        let dv = [sub3(s.v[i], s.free[i]), sub3(s.v[i + 1], s.free[i + 1])];
        r.rhs = dot3(r.k[0], dv[0]) + dot3(r.k[1], dv[1]) - (pa[c] - pb[c]) / h;
        s.rows.push(r);
    }
}

/// Candidate `index`'s rows, by its mode: none off the floor; its predicted gap (and, if it
/// sticks, its tangential velocity) on it.
fn contact_rows(chain: &ExactChain, s: &mut Scratch, index: usize, h: f64) {
    let floor = chain.floor.expect("candidates need a floor");
    let c = s.candidates[index];
    s.candidates[index].row = s.rows.len();
    if c.mode == Mode::Off {
        return;
    }
    let (n, t) = (floor.normal, floor.tangent());
    let b = c.body;
    let inv = s.inv[b];
    let arm1 = predicted_arm(s, b, c.local);
    let dn = along(n, c.arm);
    let dt = along(t, c.arm);
    let direction = match c.mode {
        Mode::Slide(sign) => {
            let mu = sign * floor.friction;
            [dn[0] - mu * dt[0], dn[1] - mu * dt[1], dn[2] - mu * dt[2]]
        }
        _ => dn,
    };
    let mut normal = row(b, along(n, arm1), direction, None);
    let gap = floor.gap(predicted_point(s, b, c.local)) - c.floor_m;
    normal.rhs = dot3(normal.k[0], sub3(s.v[b], s.free[b])) - gap / h;
    normal.reg = REGULARISATION * weighted(dn, inv, dn);
    s.rows.push(normal);
    if c.mode == Mode::Stick {
        let mut tangent = row(b, dt, dt, None);
        tangent.rhs = -dot3(dt, s.free[b]);
        tangent.reg = REGULARISATION * weighted(dt, inv, dt);
        s.rows.push(tangent);
    }
}

/// `k_r M^-1 d_c^T` over the bodies two rows share.
fn coupling(r: &Row, c: &Row, inv: &[[f64; 3]]) -> f64 {
    let mut sum = 0.0;
    for a in 0..r.count {
        for b in 0..c.count {
            if r.body[a] == c.body[b] {
                sum += weighted(r.k[a], inv[r.body[a]], c.d[b]);
            }
        }
    }
    sum
}

/// Fills the block-tridiagonal system from the rows and solves it into `x`.
fn solve_rows(chain: &mut ExactChain, s: &mut Scratch) -> Result<(), StepError> {
    let system = &mut chain.system;
    system.reset(&s.sizes);
    let blocks = s.sizes.len();
    for i in 0..blocks {
        let at = system.row_at(i);
        let size = system.size(i);
        for r in 0..size {
            let row = &s.rows[at + r];
            for c in 0..size {
                let mut a = coupling(row, &s.rows[at + c], &s.inv);
                if r == c {
                    a += row.reg;
                }
                *system.diag_mut(i, r, c) = a;
            }
            if i + 1 < blocks {
                let next = system.row_at(i + 1);
                for c in 0..system.size(i + 1) {
                    let other = &s.rows[next + c];
                    *system.upper_mut(i, r, c) = coupling(row, other, &s.inv);
                    *system.lower_mut(i, c, r) = coupling(other, row, &s.inv);
                }
            }
        }
    }
    s.x.clear();
    s.x.extend(s.rows.iter().map(|r| r.rhs));
    system
        .solve(&mut s.x)
        .map_err(|Singular { block }| StepError::Singular { block })?;
    if s.x.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(StepError::NonFinite)
    }
}

/// The iterate's velocity from the impulses `x`: `v = v_free + M^-1 D^T x`.
fn apply(s: &mut Scratch) {
    s.v.clone_from(&s.free);
    for (r, &x) in s.rows.iter().zip(&s.x) {
        for a in 0..r.count {
            let (b, d) = (r.body[a], r.d[a]);
            let w = s.inv[b];
            for k in 0..3 {
                s.v[b][k] += w[k] * d[k] * x;
            }
        }
    }
}

/// Reads each contact's impulses from `x` and chooses its mode for the next iterate.
/// Returns whether any mode changed, and the largest distance of a contact point on the
/// floor from it.
fn settle_modes(chain: &ExactChain, s: &mut Scratch, h: f64) -> (bool, f64) {
    let Some(floor) = chain.floor else {
        return (false, 0.0);
    };
    let tol = chain.tolerance.position_m;
    let mu = floor.friction;
    let (mut changed, mut worst) = (false, 0.0_f64);
    for i in 0..s.candidates.len() {
        let c = s.candidates[i];
        let (normal, tangent) = match c.mode {
            Mode::Off => (0.0, 0.0),
            Mode::Normal => (s.x[c.row], 0.0),
            Mode::Stick => (s.x[c.row], s.x[c.row + 1]),
            Mode::Slide(sign) => (s.x[c.row], -sign * mu * s.x[c.row]),
        };
        let gap = floor.gap(predicted_point(s, c.body, c.local)) - c.floor_m;
        let v = s.v[c.body];
        let slip = dot3(along(floor.tangent(), c.arm), v);
        let next = next_mode(c.mode, normal, tangent, gap, slip, mu, tol, tol / h);
        if c.mode != Mode::Off {
            worst = worst.max(gap.abs());
        }
        changed |= next != c.mode;
        let c = &mut s.candidates[i];
        (c.normal, c.tangent, c.mode) = (normal, tangent, next);
    }
    (changed, worst)
}

/// A contact's next mode: it leaves the floor if the floor pulls on it, lands if it would
/// end below it, slides if friction would leave its cone, and sticks if its slip reverses.
#[allow(clippy::too_many_arguments)]
fn next_mode(
    mode: Mode,
    normal: f64,
    tangent: f64,
    gap: f64,
    slip: f64,
    mu: f64,
    tol: f64,
    tol_speed: f64,
) -> Mode {
    let on = if mu > 0.0 { Mode::Stick } else { Mode::Normal };
    match mode {
        Mode::Off if gap < -tol => on,
        Mode::Off => Mode::Off,
        _ if normal < 0.0 => Mode::Off,
        Mode::Stick if tangent.abs() > mu * normal * (1.0 + CONE_SLACK) => {
            Mode::Slide(-tangent.signum())
        }
        Mode::Slide(sign) if sign * slip < -tol_speed => Mode::Stick,
        other => other,
    }
}

/// The widest joint gap at the iterate's predicted pose (m).
fn joint_gap(chain: &ExactChain, s: &Scratch) -> f64 {
    let mut widest: f64 = 0.0;
    for (i, j) in chain.joints.iter().enumerate() {
        let (a, b) = (
            predicted_point(s, i, j.prev),
            predicted_point(s, i + 1, j.next),
        );
        widest = widest.max((a[0] - b[0]).hypot(a[1] - b[1]));
    }
    if let Some(pin) = chain.pin {
        let a = predicted_point(s, 0, pin.anchor);
        widest = widest.max((a[0] - pin.at_m[0]).hypot(a[1] - pin.at_m[1]));
    }
    widest
}

/// Adds, on the floor, any contact point the step did not expect to reach it that would end
/// below it; returns whether there was one.
fn reach_new_points(chain: &ExactChain, s: &mut Scratch) -> bool {
    let Some(floor) = chain.floor else {
        return false;
    };
    let tol = chain.tolerance.position_m;
    let mut added = false;
    let mut next = 0;
    for (i, b) in chain.bodies.iter().enumerate() {
        for vertex in chain.vertex_at[i]..chain.vertex_at[i + 1] {
            while next < s.candidates.len() && s.candidates[next].vertex < vertex {
                next += 1;
            }
            if s.candidates.get(next).is_some_and(|c| c.vertex == vertex) {
                continue;
            }
            let local = chain.vertices[vertex];
            if floor.gap(predicted_point(s, i, local)) < -tol {
                let gap = floor.gap(b.point(local));
                let mut c = candidate(chain, vertex, i, local, b.arm(local), gap);
                c.mode = if floor.friction > 0.0 {
                    Mode::Stick
                } else {
                    Mode::Normal
                };
                s.candidates.insert(next, c);
                added = true;
            }
        }
    }
    added
}

/// Moves the bodies to the step's end, keeps the contacts' impulses and modes.
fn finish(chain: &mut ExactChain, s: &Scratch, h: f64) {
    for (b, v) in chain.bodies.iter_mut().zip(&s.v) {
        b.velocity_m_s = [v[0], v[1]];
        b.spin_rad_s = v[2];
        b.position_m = [b.position_m[0] + h * v[0], b.position_m[1] + h * v[1]];
        b.angle_rad += h * v[2];
    }
    chain.modes.fill(Mode::Off);
    chain.contacts.clear();
    let Some(floor) = chain.floor else { return };
    let (n, t) = (floor.normal, floor.tangent());
    for c in &s.candidates {
        chain.modes[c.vertex] = c.mode;
        if c.normal == 0.0 && c.tangent == 0.0 {
            continue;
        }
        chain.contacts.push(ContactImpulse {
            body: c.body,
            vertex: c.vertex - chain.vertex_at[c.body],
            normal_n_s: [n[0] * c.normal, n[1] * c.normal],
            friction_n_s: [t[0] * c.tangent, t[1] * c.tangent],
            arm_m: c.arm,
        });
    }
}
