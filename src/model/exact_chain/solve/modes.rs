//! The contacts of a step's impulse stages: the floor's points and the layers' touches
//! (`super::layers`) within reach, each with the normal velocity it may leave the stage
//! with, and the rows it gives.

use super::super::{ExactChain, StepError, Surface};
use super::layers::{self, Key, Touch};
use super::rows::{along, dot3};
use super::{Scratch, position_tolerance};

/// A contact point closer to the floor than this many position tolerances rests on it: it
/// leaves the step with no normal velocity, rather than closing its gap.
pub(in crate::model::exact_chain) const SLOP: f64 = 1000.0;

/// What a contact is with.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Source {
    /// The floor, at this vertex (an index into `ExactChain::vertices`).
    Floor(usize),
    /// A layer: the laid tape or another body, by the touch's key.
    Layer(Key),
}

/// A contact within reach this step.
#[derive(Debug, Clone, Copy)]
pub(super) struct Candidate {
    pub(super) source: Source,
    /// The body the normal points into.
    pub(super) body: usize,
    /// The other body, which takes the impulse reversed; `None`: the floor or the laid tape.
    pub(super) other: Option<usize>,
    /// Unit normal into `body` (world).
    pub(super) n: [f64; 2],
    /// Coulomb's coefficient.
    pub(super) mu: f64,
    /// The contact point's offset from `body`'s centre of mass, and from `other`'s, at the
    /// stage's pose (world, m).
    pub(super) arm: [f64; 2],
    pub(super) arm_other: [f64; 2],
    /// The slowest normal velocity it may leave the impulses at the step's start with: apart,
    /// `-gap / h`, closing its gap, no more; touching (within the slop, or overlapping: the
    /// drift's depths are moved out by position, `super::project_out`), 0; either less
    /// what gravity's half kick before the drift will add across a still surface. At the
    /// step's end, 0 (m/s).
    pub(super) target: f64,
    /// Its normal and friction impulses (N s): the last stage's as a first guess, then the
    /// solve's.
    pub(super) normal: f64,
    pub(super) tangent: f64,
}

impl Candidate {
    /// The direction along which friction is counted: the normal turned a quarter clockwise.
    pub(super) fn t(&self) -> [f64; 2] {
        [self.n[1], -self.n[0]]
    }

    /// The row of the relative velocity along `dir`: its Jacobian on `body`, and on `other`.
    pub(super) fn row(&self, dir: [f64; 2]) -> ([f64; 3], [f64; 3]) {
        (
            along(dir, self.arm),
            along([-dir[0], -dir[1]], self.arm_other),
        )
    }

    /// The relative velocity along `dir` at the velocities `v` (m/s).
    pub(super) fn speed(&self, dir: [f64; 2], v: &[[f64; 3]]) -> f64 {
        let (k, k_other) = self.row(dir);
        dot3(k, v[self.body]) + self.other.map_or(0.0, |o| dot3(k_other, v[o]))
    }

    /// The normal and tangential relative velocities at `v` (m/s).
    pub(super) fn speeds(&self, v: &[[f64; 3]]) -> [f64; 2] {
        [self.speed(self.n, v), self.speed(self.t(), v)]
    }
}

/// The target of `c`, a contact `gap` apart (m), in `stage`: before the drift, what
/// gravity's half kick in the drift will add across it is met too.
fn target(s: &Scratch, stage: Impulses, gap: f64, c: &Candidate, slop: f64) -> f64 {
    // Resting contacts, within the slop (`SLOP` position tolerances), all aim at the same
    // velocity: their targets agree, where closing each one's own microscopic gap would ask
    // a sticking body to turn.
    match stage {
        // Before the drift: close the gap over the step (or push a penetration out), and
        // meet gravity's two half kicks across the contact with the first. What a half kick
        // adds is the contact's relative velocity in `s.fall`, the kick with the joints
        // held: `-h g_n / 2` on a piece free above the floor, none between two pieces that
        // fall together, and as little as the joints let through where they hold a piece
        // (the piece pinned to the laid tape's end). Asking a held piece for the whole of
        // `h g_n / 2` would set the contact against the joints, with impulses without bound.
        Impulses::Start(h) => {
            let fall = c.speed(c.n, &s.fall);
            if gap > slop { -gap / h - fall } else { -fall }
        }
        // After the drift: touching, no approach.
        Impulses::End => 0.0,
    }
}

/// Vertex `vertex` of `body` as a candidate of the impulses at `stage`, at the stage's
/// pose (`s.start_pose`).
fn floor_candidate(
    chain: &ExactChain,
    s: &Scratch,
    (vertex, body): (usize, usize),
    stage: Impulses,
    slop: f64,
) -> Candidate {
    let local = chain.vertices[vertex];
    let floor = chain.floor.expect("candidates need a floor");
    let r = chain.radius_m();
    let gap = floor.gap(s.start_pose.point(body, local)) - r;
    let [normal, tangent] = chain.warm[vertex];
    let arm = s.start_pose.arm(body, local);
    let mut c = Candidate {
        source: Source::Floor(vertex),
        body,
        other: None,
        n: floor.normal,
        mu: floor.friction,
        // The floor meets the body at its face, `r` below the node.
        arm: [arm[0] - r * floor.normal[0], arm[1] - r * floor.normal[1]],
        arm_other: [0.0; 2],
        target: 0.0,
        normal,
        tangent,
    };
    c.target = target(s, stage, gap, &c, slop);
    c
}

/// A layers' touch as a candidate of the impulses at `stage`.
fn layer_candidate(
    chain: &ExactChain,
    s: &Scratch,
    t: &Touch,
    stage: Impulses,
    slop: f64,
) -> Candidate {
    let layers = chain.layers.as_ref().expect("touches need layers");
    let [normal, tangent] = chain
        .layer_warm
        .binary_search_by_key(&t.key, |w| w.0)
        .map_or([0.0; 2], |i| chain.layer_warm[i].1);
    let offset = |body: usize| {
        let c = s.start_pose.centre(body);
        [t.point[0] - c[0], t.point[1] - c[1]]
    };
    let mut c = Candidate {
        source: Source::Layer(t.key),
        body: t.body,
        other: t.other,
        n: t.normal,
        mu: layers.friction,
        arm: offset(t.body),
        arm_other: t.other.map_or([0.0; 2], offset),
        target: 0.0,
        normal,
        tangent,
    };
    c.target = target(s, stage, t.gap_m, &c, slop);
    c
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

/// How far each body's points may move this step: twice as far as its fastest point would
/// go at the velocities `v`, or under gravity alone (m).
fn reaches(chain: &ExactChain, s: &Scratch, v: &[[f64; 3]], h: f64) -> Vec<f64> {
    let g = s.gravity[0].hypot(s.gravity[1]);
    let layers = chain.layers.as_ref();
    chain
        .bodies
        .iter()
        .enumerate()
        .map(|(i, _)| {
            let far = layers.map_or(0.0, |l| {
                l.outlines[i]
                    .nodes
                    .iter()
                    .map(|p| p[0].hypot(p[1]))
                    .fold(0.0, f64::max)
            });
            let speed = v[i][0].abs() + v[i][1].abs() + v[i][2].abs() * far;
            2.0 * h * (speed + g * h)
        })
        .collect()
}

/// The contacts of `stage`: at the start, those within reach this step (twice as far as
/// each would go at its speed, or under gravity alone); at the end, those touching (within
/// the slop) or overlapping. The floor's in the order of their vertices, then the layers',
/// all sorted by their bodies (stable), as the active set takes them.
pub(super) fn gather(chain: &ExactChain, s: &mut Scratch, stage: Impulses) {
    s.candidates.clear();
    let slop = SLOP * position_tolerance(chain);
    if let Some(floor) = chain.floor {
        let g = s.gravity[0].hypot(s.gravity[1]);
        let r = chain.radius_m();
        for i in 0..chain.bodies.len() {
            let v = s.free[i];
            for vertex in chain.vertex_at[i]..chain.vertex_at[i + 1] {
                let local = chain.vertices[vertex];
                let gap = floor.gap(s.start_pose.point(i, local)) - r;
                let a = s.start_pose.arm(i, local);
                let within = match stage {
                    Impulses::Start(h) => {
                        let (u, w) = (v[0] - v[2] * a[1], v[1] + v[2] * a[0]);
                        gap < 2.0 * h * (u.abs() + w.abs() + g * h) + chain.tolerance.position_m
                    }
                    Impulses::End => gap <= slop,
                };
                if within {
                    let c = floor_candidate(chain, s, (vertex, i), stage, slop);
                    s.candidates.push(c);
                }
            }
        }
    }
    if chain.layers.is_some() {
        measure(chain, s);
        let mut touches = s.touches.clone();
        layers::patches(&mut touches);
        for t in &touches {
            let c = layer_candidate(chain, s, t, stage, slop);
            // A touch is within reach where its own point's relative motion can close it,
            // as a floor point is.
            let within = match stage {
                Impulses::Start(h) => {
                    let [u, w] = [[1.0, 0.0], [0.0, 1.0]].map(|d| c.speed(d, &s.free).abs());
                    let g = s.gravity[0].hypot(s.gravity[1]);
                    let fall = if c.other.is_none() { g * h } else { 0.0 };
                    t.gap_m < 2.0 * h * (u + w + fall) + chain.tolerance.position_m
                }
                Impulses::End => t.gap_m <= slop,
            };
            if within {
                s.candidates.push(c);
            }
        }
        s.candidates.sort_by(order);
    }
}

/// The layers' features a step of `h` measures ([`layers::near`]): every node and link
/// within what the bodies' velocities `v` can move them this step (twice the drift's
/// motion at those velocities, [`reaches`]).
pub(super) fn find_near(
    chain: &ExactChain,
    s: &mut Scratch,
    h: f64,
    v: &[[f64; 3]],
) -> Result<(), StepError> {
    if chain.layers.is_none() {
        return Ok(());
    }
    let tol = position_tolerance(chain);
    s.near_margin = reaches(chain, s, v, h)
        .into_iter()
        .map(|r| r + SLOP * tol)
        .collect();
    let mut near = std::mem::take(&mut s.near);
    let found = layers::near(chain, &s.start_pose, &s.near_margin, &mut near);
    s.near = near;
    s.near_generation += 1;
    found
}

/// The layers' touches of the step's features at `s.start_pose`, into `s.touches`: measured
/// once for each pose and each search.
pub(super) fn measure(chain: &ExactChain, s: &mut Scratch) {
    let now = (s.start_pose.generation, s.near_generation);
    if s.measured != Some(now) {
        let mut touches = std::mem::take(&mut s.touches);
        layers::evaluate(chain, &s.start_pose, &s.near, &mut touches);
        s.touches = touches;
        s.measured = Some(now);
    }
}

/// The candidates' order: by body, each body's floor points by vertex, then its layers'
/// touches by key.
fn order(a: &Candidate, b: &Candidate) -> std::cmp::Ordering {
    let rank = |c: &Candidate| match c.source {
        Source::Floor(v) => (c.body, 0, v, None),
        Source::Layer(k) => (c.body, 1, 0, Some(k)),
    };
    rank(a).cmp(&rank(b))
}

/// Adds any contact the step did not expect to reach that would end the drift overlapping:
/// a floor point below the floor, or a layer's touch; returns whether there was one.
pub(super) fn reach_new_points(
    chain: &ExactChain,
    s: &mut Scratch,
    stage: Impulses,
) -> Result<bool, StepError> {
    let Impulses::Start(h) = stage else {
        return Ok(false);
    };
    let tol = position_tolerance(chain);
    let slop = SLOP * tol;
    let mut added = false;
    if let Some(floor) = chain.floor {
        let mut present = vec![false; chain.vertices.len()];
        for c in &s.candidates {
            if let Source::Floor(v) = c.source {
                present[v] = true;
            }
        }
        let r = chain.radius_m();
        for i in 0..chain.bodies.len() {
            let v = s.v[i];
            let span = chain.vertex_at[i]..chain.vertex_at[i + 1];
            for (vertex, &present) in span.clone().zip(&present[span]) {
                if present {
                    continue;
                }
                let local = chain.vertices[vertex];
                let a = s.start_pose.arm(i, local);
                // Where the drift would take it: the impulses' velocity and gravity's half
                // kick.
                let fall = 0.5 * h * dot2(floor.normal, s.gravity);
                let end = floor.gap(s.start_pose.point(i, local)) - r
                    + h * (dot3(along(floor.normal, a), v) + fall);
                if end < -tol {
                    let c = floor_candidate(chain, s, (vertex, i), stage, slop);
                    s.candidates.push(c);
                    added = true;
                }
            }
        }
    }
    if chain.layers.is_some() {
        // The impulses may have sped a body beyond what the step's features were found
        // for: find them again.
        let reach = reaches(chain, s, &s.v, h);
        if reach.iter().zip(&s.near_margin).any(|(r, m)| r > m) {
            let v = s.v.clone();
            find_near(chain, s, h, &v)?;
        }
        let mut known: Vec<Key> = s
            .candidates
            .iter()
            .filter_map(|c| match c.source {
                Source::Layer(k) => Some(k),
                Source::Floor(_) => None,
            })
            .collect();
        known.sort_unstable();
        measure(chain, s);
        let touches = std::mem::take(&mut s.touches);
        for t in &touches {
            if known.binary_search(&t.key).is_ok() {
                continue;
            }
            let c = layer_candidate(chain, s, t, stage, slop);
            if t.gap_m + h * c.speed(c.n, &s.v) < -tol {
                s.candidates.push(c);
                added = true;
            }
        }
        s.touches = touches;
    }
    if added {
        s.candidates.sort_by(order);
    }
    Ok(added)
}

/// The deepest a floor point of the step lies below the floor at the step's end (m; 0 if
/// none), `s.start_pose` having been moved there.
pub(super) fn penetration(chain: &ExactChain, s: &Scratch) -> f64 {
    let Some(floor) = chain.floor else {
        return 0.0;
    };
    let r = chain.radius_m();
    s.candidates
        .iter()
        .filter_map(|c| match c.source {
            Source::Floor(v) => Some(r - floor.gap(s.start_pose.point(c.body, chain.vertices[v]))),
            Source::Layer(_) => None,
        })
        .fold(0.0, f64::max)
}

/// The deepest the layers overlap at `s.start_pose` (m; 0 if none): every feature the step
/// measures, not only its candidates.
pub(super) fn overlap(chain: &ExactChain, s: &mut Scratch) -> f64 {
    if chain.layers.is_none() {
        return 0.0;
    }
    measure(chain, s);
    let touches = std::mem::take(&mut s.touches);
    let deepest = touches.iter().map(|t| -t.gap_m).fold(0.0, f64::max);
    s.touches = touches;
    deepest
}

/// How far any body's outline node ended beyond the margin the step's layers' features were
/// found within, from where the step began (m; 0 if none, and without layers): two
/// layers each within their margins of where they were are within the search's reach of
/// each other.
pub(super) fn beyond_reach(chain: &ExactChain, s: &Scratch) -> f64 {
    let Some(layers) = chain.layers.as_ref() else {
        return 0.0;
    };
    let bodies = chain.bodies.iter().zip(&s.saved);
    let outlines = layers.outlines.iter().zip(&s.near_margin);
    bodies
        .zip(outlines)
        .map(|((now, was), (outline, margin))| {
            let moved = outline.nodes.iter().map(|&n| {
                let (a, b) = (now.point(n), was.point(n));
                (a[0] - b[0]).hypot(a[1] - b[1])
            });
            (moved.fold(0.0, f64::max) - margin).max(0.0)
        })
        .fold(0.0, f64::max)
}

/// What `c` pushed on, as the step reports it.
pub(super) fn surface(c: &Candidate) -> Surface {
    match (c.source, c.other) {
        (Source::Floor(_), _) => Surface::Floor,
        (Source::Layer(_), None) => Surface::Laid,
        (Source::Layer(_), Some(o)) => Surface::Body(o),
    }
}
