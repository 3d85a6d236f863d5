//! The floor's contact points in a step's impulse stages: which are within reach, and the
//! normal velocity each may leave the stage with.

use super::super::ExactChain;
use super::rows::{along, dot3};
use super::{Scratch, position_tolerance};

/// A contact point closer to the floor than this many position tolerances rests on it: it
/// leaves the step with no normal velocity, rather than closing its gap.
pub(in crate::model::exact_chain) const SLOP: f64 = 1000.0;

/// A contact point within reach of the floor this step.
#[derive(Debug, Clone, Copy)]
pub(super) struct Candidate {
    pub(super) vertex: usize,
    pub(super) body: usize,
    pub(super) local: [f64; 2],
    /// Its offset from the centre of mass at the step's start (world, m).
    pub(super) arm: [f64; 2],
    /// The slowest normal velocity it may leave the impulses at the step's start with: above
    /// the floor, `-gap / h`, closing its gap, no more; on it (within the slop, or below: the
    /// drift's depths are moved out by position, `super::project_out`), 0; either less
    /// what gravity's half kick before the drift will add across the floor. At the step's
    /// end, 0 (m/s).
    pub(super) target: f64,
    /// Its normal and friction impulses (N s): the last stage's as a first guess, then the
    /// solve's.
    pub(super) normal: f64,
    pub(super) tangent: f64,
}

/// Vertex `vertex` of `body` as a candidate of the impulses at `stage`, at the stage's
/// pose (`s.start_pose`).
fn candidate(
    chain: &ExactChain,
    s: &Scratch,
    (vertex, body): (usize, usize),
    stage: Impulses,
    slop: f64,
) -> Candidate {
    let local = chain.vertices[vertex];
    let floor = chain.floor.expect("candidates need a floor");
    let gap = floor.gap(s.start_pose.point(body, local));
    let [normal, tangent] = chain.warm[vertex];
    // Resting contacts, within the slop (`SLOP` position tolerances), all aim at the same
    // velocity: their targets agree, where closing each one's own microscopic gap would ask
    // a sticking body to turn.
    let target = match stage {
        // Before the drift: close the gap over the step (or push a penetration out), and
        // meet gravity's two half kicks across the floor (`-h g_n / 2` each) with the first.
        Impulses::Start(h) => {
            let fall = 0.5 * h * dot2(floor.normal, s.gravity);
            if gap > slop { -gap / h - fall } else { -fall }
        }
        // After the drift: on the floor, no approach.
        Impulses::End => 0.0,
    };
    Candidate {
        vertex,
        body,
        local,
        arm: s.start_pose.arm(body, local),
        target,
        normal,
        tangent,
    }
}

fn dot2(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}

/// Which of a step's two impulse stages the contacts are gathered for.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Impulses {
    /// At the step's start, before a drift of this length: every point within reach.
    Start(f64),
    /// At the step's end: every point on the floor (within the slop) or below it.
    End,
}

/// The contact points of `stage`: at the start, those within reach of the floor this step
/// (twice as far as each would go at its speed, or under gravity alone); at the end, those
/// on or below the floor.
pub(super) fn gather(chain: &ExactChain, s: &mut Scratch, stage: Impulses) {
    s.candidates.clear();
    let Some(floor) = chain.floor else { return };
    let g = s.gravity[0].hypot(s.gravity[1]);
    let slop = SLOP * position_tolerance(chain);
    for i in 0..chain.bodies.len() {
        let v = s.free[i];
        for vertex in chain.vertex_at[i]..chain.vertex_at[i + 1] {
            let local = chain.vertices[vertex];
            let gap = floor.gap(s.start_pose.point(i, local));
            let a = s.start_pose.arm(i, local);
            let within = match stage {
                Impulses::Start(h) => {
                    let (u, w) = (v[0] - v[2] * a[1], v[1] + v[2] * a[0]);
                    gap < 2.0 * h * (u.abs() + w.abs() + g * h) + chain.tolerance.position_m
                }
                Impulses::End => gap <= slop,
            };
            if within {
                let c = candidate(chain, s, (vertex, i), stage, slop);
                s.candidates.push(c);
            }
        }
    }
}

/// Adds, on the floor, any contact point the step did not expect to reach it that would end
/// it below the floor; returns whether there was one.
pub(super) fn reach_new_points(chain: &ExactChain, s: &mut Scratch, stage: Impulses) -> bool {
    let (Some(floor), Impulses::Start(h)) = (chain.floor, stage) else {
        return false;
    };
    let tol = position_tolerance(chain);
    let mut added = false;
    let mut next = 0;
    for i in 0..chain.bodies.len() {
        let v = s.v[i];
        for vertex in chain.vertex_at[i]..chain.vertex_at[i + 1] {
            while next < s.candidates.len() && s.candidates[next].vertex < vertex {
                next += 1;
            }
            if s.candidates.get(next).is_some_and(|c| c.vertex == vertex) {
                continue;
            }
            let local = chain.vertices[vertex];
            let a = s.start_pose.arm(i, local);
            // Where the drift would take it: the impulses' velocity and gravity's half kick.
            let fall = 0.5 * h * dot2(floor.normal, s.gravity);
            let end = floor.gap(s.start_pose.point(i, local))
                + h * (dot3(along(floor.normal, a), v) + fall);
            if end < -tol {
                let c = candidate(chain, s, (vertex, i), Impulses::Start(h), SLOP * tol);
                s.candidates.insert(next, c);
                added = true;
            }
        }
    }
    added
}

/// The deepest a contact point of the step lies below the floor at the step's end (m; 0 if
/// none), `s.start_pose` having been moved there.
pub(super) fn penetration(chain: &ExactChain, s: &Scratch) -> f64 {
    let Some(floor) = chain.floor else {
        return 0.0;
    };
    s.candidates
        .iter()
        .map(|c| -floor.gap(s.start_pose.point(c.body, c.local)))
        .fold(0.0, f64::max)
}
