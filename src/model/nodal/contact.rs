//! The floor's contacts in the nodal chain's step: each point's target, its modes (touching
//! or not; sticking or sliding), the rows its modes give, the work its impulses did, and the
//! projection of the points a landing took below the floor.
//!
//! A point touches where the step would take it below the floor: with `g` its height above
//! the floor at the step's start (zero within the slop), `s` its normal velocity there and
//! `h` the step, the midpoint rule moves it by `h (s + w) / 2` for an end velocity `w`, so
//! it touches where `w < -2 g / h - s`. Touching, its normal velocity at the step's end is
//! held at its target:
//!
//! ```text
//! target = min(-s, 0)
//! ```
//!
//! A point that comes down stops (0: it lands, plastically, within the step), its work
//! `P s / 2` with `s < 0`; one that was leaving the floor and is pulled back leaves the step
//! as fast as it came (`-s`: no work). So the floor's normal impulse `P >= 0` never does
//! positive work, and a point that stops can also stick (the target agrees with a piece
//! whose rigidity leaves the point one way to move, about a pin). A landing moves a point
//! below the floor by up to `h |s| / 2`, which the projection moves out by position
//! afterwards; a point that lands from just above stops up to as far above it.
//!
//! Friction is Coulomb's, solved as a sequence of Tresca problems (P. D. Panagiotopoulos,
//! Ing. Arch. 44, 421, 1975): within one linearisation each touching point's friction
//! bound `B` is fixed (`mu` times its normal impulse at the iterate), a sticking point's
//! tangential velocity is held at zero and its friction is free within `B`, and a sliding
//! point's friction is the known impulse `B` against its slip. Every system is then
//! symmetric and, regularised, definite in its contacts: the modes are those of a convex
//! problem, settled by block pivoting, then one mode at a time (the last broken, Murty's
//! rule), which cannot cycle. The bounds follow the normal impulses from one linearisation
//! to the next, and the step converges when they agree; a sliding point's friction may then
//! follow its normal impulse within the solve (Newton's step on the bounds' fixed point),
//! where that keeps the system regular.

use super::ContactImpulse;
use super::system::{self, Assembly, ContactRow, REGULARISATION, Solution};
use super::{NodalChain, add, dot, quarter, scale, sub};

/// A contact point closer to the floor than this many position tolerances rests on it.
const SLOP: f64 = 1000.0;

/// A normal impulse this fraction of the largest below zero lets its contact go; a friction
/// this fraction of the largest beyond its bound makes it slide.
const SLACK: f64 = 1e-9;

/// A contact point's friction on one linearisation, its bound fixed.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(super) enum Friction {
    /// Its tangential velocity held at zero, its friction free within its bound.
    Stick,
    /// Its friction `sign` times its bound, known (0: none, where the bound is zero).
    #[default]
    Free,
    /// See [`Friction::Free`]: `Slide(sign)`.
    Slide(f64),
}

/// A point's modes and force at the end of a step: the next step's first guess.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(super) struct Warm {
    touching: bool,
    friction: Friction,
    /// Its normal impulse per second of step (N).
    force: f64,
}

/// A contact point in a step.
#[derive(Debug, Clone, Copy)]
pub(super) struct Point {
    pub(super) piece: usize,
    /// Its index among its piece's points, and among all.
    pub(super) vertex: usize,
    index: usize,
    pub(super) local: [f64; 2],
    /// Its height above the floor at the step's start (m).
    gap0: f64,
    /// Its normal and tangential velocity at the step's start (m/s).
    start: [f64; 2],
    /// Its normal velocity's target at the step's end (m/s).
    target: f64,
    /// The end's normal velocity below which it would end below the floor, or below its
    /// target if that is lower (m/s): it touches only then.
    reach: f64,
    /// Its friction bound on this linearisation (N s).
    bound: f64,
    /// Whether its normal velocity is held at its target (its normal impulse free, `>= 0`).
    touching: bool,
    /// Whether, sliding, its friction is `mu` times its normal impulse within the solve (its
    /// column the normal's and the friction's), not its bound.
    coupled: bool,
    friction: Friction,
    /// Its normal and friction impulse (N s).
    pub(super) impulse: [f64; 2],
    /// Its first row among the assembly's contact rows, where it has one.
    row: usize,
}

impl Point {
    /// Its friction's sign where known (sliding, or none).
    fn known_friction(&self) -> Option<f64> {
        match self.friction {
            Friction::Stick => None,
            Friction::Free => Some(0.0),
            Friction::Slide(sign) => Some(sign),
        }
    }
}

/// The step's contact points, and the projection's working memory, kept from step to step.
#[derive(Debug, Default)]
pub(super) struct Contacts {
    pub(super) points: Vec<Point>,
    assembly: Assembly,
    solution: Solution,
}

/// The floor's friction coefficient in the step now being taken (0 where it is taken
/// without friction).
pub(super) fn friction(chain: &NodalChain) -> f64 {
    match chain.floor {
        Some(floor) if !chain.frictionless => floor.friction,
        _ => 0.0,
    }
}

/// Every contact point's data at the step's start (the chain's state), its modes the last
/// step's and its friction bound from the last step's normal force.
pub(super) fn prepare(chain: &NodalChain, points: &mut Vec<Point>, h: f64) {
    points.clear();
    let Some(floor) = chain.floor else { return };
    let (n, t) = (floor.normal, floor.tangent());
    let mu = friction(chain);
    let slop = SLOP * chain.position_tolerance_m();
    for i in 0..chain.pieces.len() {
        for (vertex, &local) in chain.points(i).iter().enumerate() {
            let index = chain.point_at[i] + vertex;
            let gap0 = dot(n, sub(chain.point(i, local), floor.point_m));
            let v = chain.point_velocity(i, local);
            let start = [dot(n, v), dot(t, v)];
            let height = if gap0 > slop { gap0 } else { 0.0 };
            let warm = chain.warm[index];
            let target = (-start[0]).min(0.0);
            // Friction acts on a point that comes down or rests, not on one that was
            // leaving the floor and is pulled back (its normal impulse only turns it, with no
            // work: a graze, not a landing).
            let mu = if target < 0.0 { 0.0 } else { mu };
            let bound = mu * warm.force * h;
            points.push(Point {
                piece: i,
                vertex,
                index,
                local,
                gap0,
                start,
                target,
                reach: (-2.0 * height / h - start[0]).min(-start[0]).min(0.0),
                bound,
                touching: warm.touching,
                coupled: false,
                friction: if bound > 0.0 && warm.touching {
                    warm.friction
                } else {
                    Friction::Free
                },
                impulse: [0.0; 2],
                row: 0,
            });
        }
    }
}

/// The rows of the points, at the iterate's velocities `v`: a touching point's normal row,
/// a sticking point's tangential row; a sliding point's friction, known, is added to
/// `node_rhs` (the momentum rows' right-hand side).
pub(super) fn rows(
    chain: &NodalChain,
    points: &mut [Point],
    v: &[[f64; 2]],
    out: &mut Vec<ContactRow>,
    node_rhs: &mut [[f64; 2]],
) {
    let Some(floor) = chain.floor else { return };
    let (n, t, mu) = (floor.normal, floor.tangent(), friction(chain));
    for p in points.iter_mut() {
        p.row = out.len();
        let w = super::material(v, p.piece, p.local);
        let reg = REGULARISATION * 4.0 / chain.pieces[p.piece].mass_kg;
        let row = |dir: [f64; 2], target: f64| ContactRow {
            piece: p.piece,
            local: p.local,
            read: dir,
            act: dir,
            rhs: target - dot(dir, w),
            reg,
        };
        if let (true, Friction::Slide(sign)) = (p.coupled, p.friction) {
            out.push(ContactRow {
                act: add(n, scale(sign * mu, t)),
                ..row(n, p.target)
            });
            continue;
        }
        if p.touching {
            out.push(row(n, p.target));
        }
        match p.known_friction() {
            None => out.push(row(t, 0.0)),
            Some(sign) if sign != 0.0 => add_force(p, scale(sign * p.bound, t), node_rhs),
            Some(_) => {}
        }
    }
}

/// Adds the impulse `f` at point `p` to the nodes' vectors `r` (shared between its piece's
/// nodes as the point's place on the chord shares it).
fn add_force(p: &Point, f: [f64; 2], r: &mut [[f64; 2]]) {
    let [alpha, beta] = p.local;
    let j = quarter(f);
    r[p.piece] = add(r[p.piece], add(scale(1.0 - alpha, f), scale(beta, j)));
    r[p.piece + 1] = add(r[p.piece + 1], sub(scale(alpha, f), scale(beta, j)));
}

/// Couples the friction of the sliding points that touch to their normal impulse within
/// the solve (or uncouples every point); whether any point's coupling changed.
pub(super) fn couple(points: &mut [Point], on: bool) -> bool {
    let mut changed = false;
    for p in points {
        let coupled = on
            && p.touching
            && p.target == 0.0
            && matches!(p.friction, Friction::Slide(s) if s != 0.0);
        changed |= coupled != p.coupled;
        p.coupled = coupled;
    }
    changed
}

/// Whether any point touches (its normal row is in the system).
pub(super) fn any_touching(points: &[Point]) -> bool {
    points.iter().any(|p| p.touching)
}

/// Reads each point's impulses from the last solve (`mu` the floor's friction).
pub(super) fn take_impulses(points: &mut [Point], x: &[f64], mu: f64) {
    for p in points {
        if let (true, Friction::Slide(sign)) = (p.coupled, p.friction) {
            p.impulse = [x[p.row], sign * mu * x[p.row]];
            continue;
        }
        let mut row = p.row;
        let normal = if p.touching {
            row += 1;
            x[row - 1]
        } else {
            0.0
        };
        let friction = match p.known_friction() {
            None => x[row],
            Some(sign) => sign * p.bound,
        };
        p.impulse = [normal, friction];
    }
}

/// Subtracts the points' impulses from the nodes' momentum residuals `r`.
pub(super) fn subtract_forces(chain: &NodalChain, points: &[Point], r: &mut [[f64; 2]]) {
    let Some(floor) = chain.floor else { return };
    let (n, t) = (floor.normal, floor.tangent());
    for p in points {
        if p.impulse != [0.0; 2] {
            let f = add(scale(p.impulse[0], n), scale(p.impulse[1], t));
            add_force(p, scale(-1.0, f), r);
        }
    }
}

/// The squared misses of the points' rows at the velocities `v` (m^2/s^2).
pub(super) fn row_residuals(chain: &NodalChain, points: &[Point], v: &[[f64; 2]]) -> f64 {
    let Some(floor) = chain.floor else { return 0.0 };
    let (n, t) = (floor.normal, floor.tangent());
    let mut sum = 0.0;
    for p in points {
        let w = super::material(v, p.piece, p.local);
        if p.touching {
            sum += (dot(n, w) - p.target).powi(2);
        }
        if p.friction == Friction::Stick {
            sum += dot(t, w).powi(2);
        }
    }
    sum
}

/// Changes the modes a linear solution (velocities `v`, the points' impulses) breaks, with
/// the friction bounds fixed, the normal and the friction of a point apart (Tresca's
/// problem is a convex one in both); returns how many changed. A point off goes on where it
/// would end below its target, a point on goes off where its normal impulse pulls; a
/// sticking point slides where its friction passes its bound, a sliding point sticks where
/// its slip runs along its friction. Every broken mode changes (block pivoting), or where
/// `single`, the last broken alone (Murty's rule).
pub(super) fn select(
    chain: &NodalChain,
    points: &mut [Point],
    v: &[[f64; 2]],
    tol_speed: f64,
    single: bool,
) -> usize {
    let Some(floor) = chain.floor else {
        return 0;
    };
    let (n, t) = (floor.normal, floor.tangent());
    let largest = points
        .iter()
        .map(|p| p.impulse[0].abs().max(p.impulse[1].abs()))
        .fold(0.0, f64::max);
    let slack = SLACK * largest;
    // (point, whether its normal or its friction breaks, and the mended mode).
    let mut broken: Vec<(usize, Option<bool>, Option<Friction>)> = Vec::new();
    for (k, p) in points.iter().enumerate() {
        let w = super::material(v, p.piece, p.local);
        let (w_n, slip) = (dot(n, w), dot(t, w));
        let [p_n, p_t] = p.impulse;
        let touching = match p.touching {
            false if w_n < p.reach - tol_speed => Some(true),
            true if p_n < -slack => Some(false),
            _ => None,
        };
        let friction = match p.friction {
            _ if p.bound <= 0.0 => (p.friction != Friction::Free).then_some(Friction::Free),
            Friction::Stick if p_t.abs() > p.bound + slack => Some(Friction::Slide(p_t.signum())),
            Friction::Free => Some(Friction::Stick),
            Friction::Slide(sign) if sign * slip > tol_speed => Some(Friction::Stick),
            _ => None,
        };
        if touching.is_some() || friction.is_some() {
            broken.push((k, touching, friction));
        }
    }
    if single && broken.len() > 1 {
        broken.drain(..broken.len() - 1);
    }
    for &(k, touching, friction) in &broken {
        let p = &mut points[k];
        if let Some(on) = touching {
            p.touching = on;
        }
        if let Some(f) = friction {
            p.friction = f;
        }
    }
    broken.len()
}

/// Moves each point's friction bound towards `mu` times its normal impulse: a sliding
/// point's (whose friction is its bound) the fraction `relax` of the way, any other's all of
/// it. Returns by how much Coulomb's law was missed, over the largest normal impulse (0 if
/// none pushes): a sliding point's friction against `mu` times its normal impulse, a
/// sticking point's friction beyond it.
pub(super) fn update_bounds(chain: &NodalChain, points: &mut [Point], relax: f64) -> f64 {
    let mu = friction(chain);
    let (mut miss, mut largest) = (0.0_f64, 0.0_f64);
    for p in points.iter_mut() {
        let bound = if p.target < 0.0 {
            0.0
        } else {
            mu * p.impulse[0].max(0.0)
        };
        largest = largest.max(p.impulse[0].abs());
        match p.friction {
            Friction::Slide(_) if !p.coupled => {
                miss = miss.max((bound - p.bound).abs());
                p.bound += relax * (bound - p.bound);
            }
            Friction::Stick => {
                miss = miss.max(p.impulse[1].abs() - bound);
                p.bound = bound;
            }
            _ => p.bound = bound,
        }
    }
    if largest > 0.0 { miss / largest } else { 0.0 }
}

/// Records the step's contacts with their work (each impulse times its point's mean
/// velocity over the step), keeps the modes for the next step; returns the normal's and
/// friction's work (J). The chain's nodes and velocities are the step's end.
pub(super) fn record(
    chain: &mut NodalChain,
    points: &[Point],
    x0: &[[f64; 2]],
    h: f64,
) -> [f64; 2] {
    chain.contacts.clear();
    let Some(floor) = chain.floor else {
        return [0.0; 2];
    };
    let (n, t) = (floor.normal, floor.tangent());
    let x_mid: Vec<[f64; 2]> = chain
        .nodes
        .iter()
        .zip(x0)
        .map(|(a, b)| scale(0.5, add(*a, *b)))
        .collect();
    let mut total = [0.0; 2];
    for p in points {
        chain.warm[p.index] = Warm {
            touching: p.touching,
            friction: p.friction,
            force: p.impulse[0].max(0.0) / h,
        };
        if p.impulse == [0.0; 2] {
            continue;
        }
        let w = chain.point_velocity(p.piece, p.local);
        let work = [
            p.impulse[0] * 0.5 * (p.start[0] + dot(n, w)),
            p.impulse[1] * 0.5 * (p.start[1] + dot(t, w)),
        ];
        total = add(total, work);
        let c = contact_impulse(chain, &x_mid, p, work);
        chain.contacts.push(c);
    }
    total
}

/// Moves the nodes, not their velocities, so that no point lies deeper below the floor
/// than the slop (or than it began the step, if deeper), keeping the pieces rigid: the
/// least move in the mass matrix's norm, by the same banded solve, a few times over if the
/// move takes other points below. Returns the potential energy it added (J) and whether it
/// converged.
pub(super) fn project_out(
    chain: &mut NodalChain,
    c: &mut Contacts,
    kick: &[[f64; 2]],
    h: f64,
) -> Result<(f64, bool), super::StepError> {
    let Some(floor) = chain.floor else {
        return Ok((0.0, true));
    };
    let n = floor.normal;
    let tol = chain.position_tolerance_m();
    let deepest = SLOP * tol;
    let before = chain.nodes.clone();
    // (point, the height it is moved to), in the points' order.
    let mut deep: Vec<(usize, f64)> = Vec::new();
    let gap =
        |chain: &NodalChain, p: &Point| dot(n, sub(chain.point(p.piece, p.local), floor.point_m));
    let mut closed = false;
    for _ in 0..chain.tolerance.max_iterations {
        let mut added = false;
        for (k, p) in c.points.iter().enumerate() {
            let floor_at = p.gap0.min(0.0);
            if gap(chain, p) < floor_at - deepest && !deep.iter().any(|d| d.0 == k) {
                deep.push((k, floor_at));
                added = true;
            }
        }
        if deep.is_empty() {
            return Ok((0.0, true));
        }
        if added {
            deep.sort_by_key(|d| d.0);
        }
        let holds = deep
            .iter()
            .all(|&(k, at)| (gap(chain, &c.points[k]) - at).abs() <= tol);

        if holds && chain.length_error_m() <= tol {
            closed = true;
            break;
        }
        let a = &mut c.assembly;
        a.clear(true, chain.pieces.len());
        for (i, p) in chain.pieces.iter().enumerate() {
            let d = sub(chain.nodes[i + 1], chain.nodes[i]);
            let l = p.length_m;
            a.col.push(scale(1.0 / l, d));
            a.row.push(scale(1.0 / l, d));
            a.chord_rhs.push(-0.5 * (dot(d, d) - l * l) / l);
        }
        let moved: Vec<[f64; 2]> = chain
            .nodes
            .iter()
            .zip(&before)
            .map(|(x, b)| sub(*x, *b))
            .collect();
        let pull = system::times_mass(&chain.pieces, &moved);
        a.node_rhs.extend(pull.iter().map(|m| scale(-1.0, *m)));
        for &(k, at) in &deep {
            let p = &c.points[k];
            a.contacts.push(ContactRow {
                piece: p.piece,
                local: p.local,
                read: n,
                act: n,
                rhs: at - gap(chain, p),
                reg: REGULARISATION * 4.0 / chain.pieces[p.piece].mass_kg,
            });
        }
        system::solve(
            &chain.pieces,
            chain.pinned,
            &mut chain.system,
            &c.assembly,
            &mut c.solution,
        )?;
        for (x, d) in chain.nodes.iter_mut().zip(&c.solution.delta) {
            *x = add(*x, *d);
        }
    }
    // A projection that did not close (points of one piece that began the step at depths
    // its rigidity cannot all keep) is not kept: its last iterate may open the pieces. The
    // points stay as deep as the step left them.
    if !closed {
        chain.nodes = before;
        return Ok((0.0, false));
    }
    // The potential is -f . x, and kick = h f.
    let lift: f64 = chain
        .nodes
        .iter()
        .zip(&before)
        .zip(kick)
        .map(|((x, b), k)| -dot(*k, sub(*x, *b)))
        .sum();
    Ok((lift / h, closed))
}

/// The deepest a contact point lies below the floor (m; 0 if none).
pub(super) fn penetration(chain: &NodalChain, points: &[Point]) -> f64 {
    let Some(floor) = chain.floor else { return 0.0 };
    points
        .iter()
        .map(|p| {
            -dot(
                floor.normal,
                sub(chain.point(p.piece, p.local), floor.point_m),
            )
        })
        .fold(0.0, f64::max)
}

/// A point's impulses over the step as the chain reports them (`x_mid` the nodes at the
/// step's midpoint).
fn contact_impulse(
    chain: &NodalChain,
    x_mid: &[[f64; 2]],
    point: &Point,
    work_j: [f64; 2],
) -> ContactImpulse {
    let floor = chain.floor.expect("contacts need a floor");
    let (n, t) = (floor.normal, floor.tangent());
    let p = &chain.pieces[point.piece];
    let at = super::material(x_mid, point.piece, point.local);
    let centre = super::material(x_mid, point.piece, p.centre);
    ContactImpulse {
        piece: point.piece,
        vertex: point.vertex,
        normal_n_s: scale(point.impulse[0], n),
        friction_n_s: scale(point.impulse[1], t),
        point_m: at,
        arm_m: sub(at, centre),
        work_j,
    }
}
