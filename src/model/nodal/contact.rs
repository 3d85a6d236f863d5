//! The floor's contacts in the nodal chain's step: each point's target, its mode (off,
//! sticking, sliding) chosen within the Newton iterations by Alart and Curnier's rule, the
//! rows its mode gives, the work its impulses did, and the projection of the points a
//! landing took below the floor.
//!
//! A point's normal velocity at the step's end is held at its target where it touches.
//! With `g` its height above the floor at the step's start (zero within the slop), `s` its
//! normal velocity there and `h` the step (the midpoint rule moves it by `h (s + w) / 2`
//! for an end velocity `w`):
//!
//! ```text
//! target = min(-2 g / h - s, 0)
//! ```
//!
//! Above the floor, a point that would pass it arrives at it (the first term), its work
//! `-P g / h`; one that would pass it even stopped stops (0: it lands, plastically), its
//! work `P s / 2` with `s < 0`; on the floor, a point stops (0), or, if it was leaving the
//! floor and is pulled back, leaves the step as fast as it came (`-s`: no work). So the
//! floor's normal impulse `P >= 0` never does positive work. A landing moves a point below
//! the floor by up to `h |s| / 2`; the projection moves it out by position afterwards.

use super::newton::{self, ContactRow, REGULARISATION, Scratch};
use super::{NodalChain, add, dot, quarter, scale, sub};

/// A contact point closer to the floor than this many position tolerances rests on it.
const SLOP: f64 = 1000.0;

/// A normal impulse this fraction of the largest below zero lets its contact go; a friction
/// this fraction beyond its cone makes it slide.
const SLACK: f64 = 1e-9;

/// A contact point's mode.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub enum Mode {
    /// Not touching.
    #[default]
    Off,
    /// Touching, its tangential velocity held at zero.
    Stick,
    /// Touching and sliding: its friction impulse `sign * mu` times its normal one.
    Slide(f64),
}

/// A point's mode and impulses at the end of a step: the next step's first guess.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(super) struct Warm {
    mode: Mode,
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
    /// Alart and Curnier's factor: about the point's effective mass (kg).
    mass: f64,
    mode: Mode,
    /// Its normal and friction impulse (N s).
    pub(super) impulse: [f64; 2],
    /// Its first row among the assembly's contact rows, where it is on.
    row: usize,
}

/// Every contact point's data at the step's start (the chain's state), its mode the last
/// step's.
pub(super) fn prepare(chain: &NodalChain, s: &mut Scratch, h: f64) {
    s.points.clear();
    let Some(floor) = chain.floor else { return };
    let (n, t) = (floor.normal, floor.tangent());
    let slop = SLOP * chain.position_tolerance_m();
    for i in 0..chain.pieces.len() {
        for (vertex, &local) in chain.points(i).iter().enumerate() {
            let index = chain.point_at[i] + vertex;
            let gap0 = dot(n, sub(chain.point(i, local), floor.point_m));
            let v = chain.point_velocity(i, local);
            let start = [dot(n, v), dot(t, v)];
            let reach = if gap0 > slop { gap0 } else { 0.0 };
            s.points.push(Point {
                piece: i,
                vertex,
                index,
                local,
                gap0,
                start,
                target: (-2.0 * reach / h - start[0]).min(0.0),
                mass: 0.5 * chain.pieces[i].mass_kg,
                mode: chain.warm[index].mode,
                impulse: [0.0; 2],
                row: 0,
            });
        }
    }
}

/// The rows of the points that are on, at the iterate's velocities `v`.
pub(super) fn rows(
    chain: &NodalChain,
    points: &mut [Point],
    v: &[[f64; 2]],
    out: &mut Vec<ContactRow>,
) {
    let Some(floor) = chain.floor else { return };
    let (n, t, mu) = (floor.normal, floor.tangent(), floor.friction);
    for p in points.iter_mut() {
        if p.mode == Mode::Off {
            continue;
        }
        p.row = out.len();
        let w = super::material(v, p.piece, p.local);
        let reg = REGULARISATION * 4.0 / chain.pieces[p.piece].mass_kg;
        let row = |read: [f64; 2], act: [f64; 2], target: f64| ContactRow {
            piece: p.piece,
            local: p.local,
            read,
            act,
            rhs: target - dot(read, w),
            reg,
        };
        match p.mode {
            Mode::Off => {}
            Mode::Stick => out.extend([row(n, n, p.target), row(t, t, 0.0)]),
            Mode::Slide(sign) => out.push(row(n, add(n, scale(sign * mu, t)), p.target)),
        }
    }
}

/// Reads each point's impulses from the last solve.
pub(super) fn take_impulses(chain: &NodalChain, s: &mut Scratch) {
    let mu = chain.floor.map_or(0.0, |f| f.friction);
    let x = &s.solution.contact;
    for p in &mut s.points {
        p.impulse = match p.mode {
            Mode::Off => [0.0; 2],
            Mode::Stick => [x[p.row], x[p.row + 1]],
            Mode::Slide(sign) => [x[p.row], sign * mu * x[p.row]],
        };
    }
}

/// Subtracts the points' impulses from the nodes' momentum residuals `r` (each impulse
/// shared between its piece's nodes as the point's place on the chord shares it).
pub(super) fn subtract_forces(chain: &NodalChain, points: &[Point], r: &mut [[f64; 2]]) {
    let Some(floor) = chain.floor else { return };
    let (n, t) = (floor.normal, floor.tangent());
    for p in points {
        if p.impulse == [0.0; 2] {
            continue;
        }
        let f = add(scale(p.impulse[0], n), scale(p.impulse[1], t));
        let [alpha, beta] = p.local;
        let j = quarter(f);
        r[p.piece] = sub(r[p.piece], add(scale(1.0 - alpha, f), scale(beta, j)));
        r[p.piece + 1] = sub(r[p.piece + 1], sub(scale(alpha, f), scale(beta, j)));
    }
}

/// The squared misses of the rows of the points that are on, at the velocities `v` (m^2/s^2).
pub(super) fn row_residuals(chain: &NodalChain, points: &[Point], v: &[[f64; 2]]) -> f64 {
    let Some(floor) = chain.floor else { return 0.0 };
    let (n, t) = (floor.normal, floor.tangent());
    let mut sum = 0.0;
    for p in points {
        if p.mode == Mode::Off {
            continue;
        }
        let w = super::material(v, p.piece, p.local);
        sum += (dot(n, w) - p.target).powi(2);
        if p.mode == Mode::Stick {
            sum += dot(t, w).powi(2);
        }
    }
    sum
}

/// Changes the modes the iterate breaks (Alart and Curnier's rule); whether any changed. A
/// point off goes on where it would end below its target; a point on goes off where its
/// normal impulse pulls; a sticking point slides where its friction leaves the cone; a
/// sliding point whose slip runs along its friction sticks, or slides the other way if its
/// slip is too fast for the cone to stop.
pub(super) fn select(chain: &NodalChain, s: &mut Scratch, tol_speed: f64) -> bool {
    let Some(floor) = chain.floor else {
        return false;
    };
    let (n, t, mu) = (floor.normal, floor.tangent(), floor.friction);
    let largest = s
        .points
        .iter()
        .map(|p| p.impulse[0].abs())
        .fold(0.0, f64::max);
    let slack = SLACK * largest;
    let mut changed = false;
    for p in &mut s.points {
        let w = super::material(&s.v, p.piece, p.local);
        let (w_n, w_t) = (dot(n, w), dot(t, w));
        let [p_n, p_t] = p.impulse;
        let next = match p.mode {
            Mode::Off if w_n < p.target - tol_speed => {
                if mu > 0.0 {
                    Mode::Stick
                } else {
                    Mode::Slide(0.0)
                }
            }
            Mode::Off => Mode::Off,
            _ if p_n < -slack => Mode::Off,
            Mode::Stick if p_t.abs() > mu * p_n + slack => Mode::Slide(p_t.signum()),
            Mode::Slide(sign) if mu > 0.0 && sign * w_t > tol_speed => {
                if p.mass * w_t.abs() <= 2.0 * mu * p_n {
                    Mode::Stick
                } else {
                    Mode::Slide(-sign)
                }
            }
            mode => mode,
        };
        if next != p.mode {
            changed = true;
            p.mode = next;
            if next == Mode::Off {
                p.impulse = [0.0; 2];
            }
        }
    }
    changed
}

/// Records the step's contacts with their work (each impulse times its point's mean
/// velocity over the step), keeps the modes for the next step; returns the normal's and
/// friction's work (J). The chain's nodes and velocities are the step's end.
pub(super) fn record(chain: &mut NodalChain, s: &Scratch) -> [f64; 2] {
    chain.contacts.clear();
    let Some(floor) = chain.floor else {
        return [0.0; 2];
    };
    let (n, t) = (floor.normal, floor.tangent());
    let x_mid: Vec<[f64; 2]> = chain
        .nodes
        .iter()
        .zip(&s.x0)
        .map(|(a, b)| scale(0.5, add(*a, *b)))
        .collect();
    let mut total = [0.0; 2];
    for p in &s.points {
        chain.warm[p.index] = Warm { mode: p.mode };
        if p.impulse == [0.0; 2] {
            continue;
        }
        let w = chain.point_velocity(p.piece, p.local);
        let work = [
            p.impulse[0] * 0.5 * (p.start[0] + dot(n, w)),
            p.impulse[1] * 0.5 * (p.start[1] + dot(t, w)),
        ];
        total = add(total, work);
        let c = newton::contact_impulse(chain, &x_mid, p, work);
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
    s: &mut Scratch,
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
        for (k, p) in s.points.iter().enumerate() {
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
            .all(|&(k, at)| (gap(chain, &s.points[k]) - at).abs() <= tol);
        if holds && chain.length_error_m() <= tol {
            closed = true;
            break;
        }
        let a = &mut s.assembly;
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
        let pull = newton::times_mass(&chain.pieces, &moved);
        a.node_rhs.extend(pull.iter().map(|m| scale(-1.0, *m)));
        for &(k, at) in &deep {
            let p = &s.points[k];
            a.contacts.push(ContactRow {
                piece: p.piece,
                local: p.local,
                read: n,
                act: n,
                rhs: at - gap(chain, p),
                reg: REGULARISATION * 4.0 / chain.pieces[p.piece].mass_kg,
            });
        }
        newton::solve(
            &chain.pieces,
            chain.pinned,
            &mut chain.system,
            &s.assembly,
            &mut s.solution,
        )?;
        for (x, d) in chain.nodes.iter_mut().zip(&s.solution.delta) {
            *x = add(*x, *d);
        }
    }
    let h_f = &s.kick;
    // The potential is -f . x, and kick = h f: the step's length cancels in the ratio of
    // the move's work to the kick's (both are read per unit of h below).
    let lift: f64 = chain
        .nodes
        .iter()
        .zip(&before)
        .zip(h_f)
        .map(|((x, b), k)| -dot(*k, sub(*x, *b)))
        .sum();
    Ok((lift / s.h, closed))
}

/// The deepest a contact point lies below the floor (m; 0 if none).
pub(super) fn penetration(chain: &NodalChain, s: &Scratch) -> f64 {
    let Some(floor) = chain.floor else { return 0.0 };
    s.points
        .iter()
        .map(|p| {
            -dot(
                floor.normal,
                sub(chain.point(p.piece, p.local), floor.point_m),
            )
        })
        .fold(0.0, f64::max)
}
