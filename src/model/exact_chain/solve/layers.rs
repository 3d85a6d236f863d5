//! Where the tape's layers touch ([`Layers`]): which node of one body comes within reach of
//! a link of another body, or of the laid tape, and how far apart their faces are.
//!
//! A body is a chain of capsules of the tape's half thickness `r` about its links, so two
//! layers touch where a node of one comes within `2 r` of a link of the other (the closest
//! points of two segments that do not cross include an end of one of them). The contact's
//! normal is along the line from the link's closest point to the node, its point halfway
//! between them: where the two faces meet. Two points of the tape closer along it than
//! [`Layers::exclusion_m`] never meet, so a tight turn's neighbouring links, which overlap
//! by geometry, are not a contact; bodies joined to each other meet only beyond it. How far
//! apart along the tape a node and its closest point on a link are is read once a step, at
//! its start, where the step finds its features: a feature counts for a whole step or not
//! at all.
//!
//! The laid tape's last node, where the first body is pinned, is met as a node of the laid
//! tape: a body folded back across the pin touches it there.
//!
//! A step searches once, at its start, for every node and link within a margin of each
//! other that covers what the step can move them ([`near`]); every pose of the step then
//! measures those features alone ([`evaluate`]), each in constant time. The search's pairs
//! come from a sort-and-sweep along `x` over the bodies' bounding boxes, and the laid
//! tape's links, sorted once by their left ends, by bisection: near linear in the bodies.
//! A search that finds more than [`FEATURES_PER_NODE`] features for each of the bodies'
//! nodes stops the step ([`StepError::Unbounded`]): its margins have outgrown the tape.

use super::super::{ExactChain, Layers, StepError};
use super::rows::Pose;

/// What a contact joins: a node (its owner, and its index in the owner's outline) and a
/// link (its owner, and the index of its first node). An owner is a body's index, or
/// [`LAID`] for the laid tape.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub(in crate::model::exact_chain) struct Key {
    node: [u32; 2],
    link: [u32; 2],
}

/// The most features a step's search may find for each node of the moving bodies (and at
/// least 65,536 in all). A margin covers what a body can move in the step, so a velocity
/// that has diverged (a contact solve gone wrong, a body at 1e20 m/s) would have it measure
/// every pair of the tape and the laid tape, and take gigabytes. The densest stacks the
/// shipped and hard scenes measure reach 15-88 a node (yoga-mat 15, thin-tape 15,
/// hard/thin-300 88): the bound is six times the largest, 8 MB for the thin tape's 1000
/// nodes.
pub(in crate::model::exact_chain) const FEATURES_PER_NODE: usize = 512;

/// The laid tape's owner index in a [`Key`].
const LAID: u32 = u32::MAX;

/// Two layers within reach of each other: which, where, and how far apart.
#[derive(Debug, Clone, Copy)]
pub(super) struct Touch {
    pub(super) key: Key,
    /// The body the normal points into.
    pub(super) body: usize,
    /// The body on the other side; `None`: the laid tape.
    pub(super) other: Option<usize>,
    /// Unit normal, from the other side into `body`.
    pub(super) normal: [f64; 2],
    /// How far apart the two faces are along the normal (m; negative: they overlap).
    pub(super) gap_m: f64,
    /// Where the faces meet: halfway between the node and its closest point on the link
    /// (world, m).
    pub(super) point: [f64; 2],
}

/// The laid tape's links sorted by their left ends, for the search by bisection.
#[derive(Debug, Default)]
pub(in crate::model::exact_chain) struct LaidIndex {
    /// Each link's index (its first node's), by its left end.
    order: Vec<u32>,
    /// The left ends, in that order (m).
    left: Vec<f64>,
    /// The widest link along `x` (m).
    widest: f64,
}

impl LaidIndex {
    /// The index of `layers`' laid tape.
    pub(in crate::model::exact_chain) fn new(layers: &Layers) -> Self {
        let nodes = &layers.laid.nodes;
        let mut order: Vec<u32> = (0..nodes.len().saturating_sub(1) as u32).collect();
        let left_of = |k: u32| nodes[k as usize][0].min(nodes[k as usize + 1][0]);
        order.sort_by(|&a, &b| left_of(a).total_cmp(&left_of(b)));
        let left = order.iter().map(|&k| left_of(k)).collect();
        let widest = (1..nodes.len())
            .map(|k| (nodes[k][0] - nodes[k - 1][0]).abs())
            .fold(0.0, f64::max);
        Self {
            order,
            left,
            widest,
        }
    }
}

/// The closest point to `p` on the segment from `q` to `r`, and its parameter in `[0, 1]`.
fn closest_on(p: [f64; 2], q: [f64; 2], r: [f64; 2]) -> ([f64; 2], f64) {
    let e = [r[0] - q[0], r[1] - q[1]];
    let length2 = e[0] * e[0] + e[1] * e[1];
    let t = if length2 > 0.0 {
        (((p[0] - q[0]) * e[0] + (p[1] - q[1]) * e[1]) / length2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    ([q[0] + t * e[0], q[1] + t * e[1]], t)
}

/// A bounding box `[min x, min y, max x, max y]` (m).
type Aabb = [f64; 4];

fn overlaps(a: &Aabb, b: &Aabb) -> bool {
    a[0] <= b[2] && b[0] <= a[2] && a[1] <= b[3] && b[1] <= a[3]
}

/// The search's working memory and its constants for one pose.
struct Search<'a> {
    layers: &'a Layers,
    /// Every body's outline nodes in the world, body by body.
    world: Vec<[f64; 2]>,
    /// Where body `i`'s nodes start in `world` (one more entry than bodies).
    at: Vec<usize>,
    margin: &'a [f64],
    /// Whether the first body is pinned at its first node.
    pinned: bool,
}

/// One side of a pair: a body's outline in the world, or the laid tape's.
#[derive(Clone, Copy)]
struct Side<'a> {
    owner: u32,
    nodes: &'a [[f64; 2]],
    /// Each node's arc length along the tape (m).
    arcs: &'a [f64],
    margin: f64,
    /// Whether its first node is a point of its own (else the side before it holds it).
    first_node: bool,
}

impl Search<'_> {
    fn side(&self, i: usize) -> Side<'_> {
        Side {
            owner: i as u32,
            nodes: &self.world[self.at[i]..self.at[i + 1]],
            arcs: &self.layers.outlines[i].arc_m,
            margin: self.margin[i],
            // The first body's first node is its own, unless the pin holds it still.
            first_node: i == 0 && !self.pinned,
        }
    }

    /// Every node of `a` among `nodes` against every link of `b` among `links` whose faces
    /// are within the two sides' margins, and whose closest points are at least
    /// [`Layers::exclusion_m`] apart along the tape, into `out`.
    fn nodes_on_links(
        &self,
        (a, nodes): (Side<'_>, std::ops::Range<usize>),
        (b, links): (Side<'_>, std::ops::Range<usize>),
        out: &mut Vec<Key>,
    ) {
        let within = 2.0 * self.layers.radius_m + a.margin + b.margin;
        for n in nodes {
            if n == 0 && !a.first_node {
                continue;
            }
            let p = a.nodes[n];
            for k in links.clone() {
                let (c, t) = closest_on(p, b.nodes[k], b.nodes[k + 1]);
                let d = [p[0] - c[0], p[1] - c[1]];
                let arc = || b.arcs[k] + t * (b.arcs[k + 1] - b.arcs[k]);
                if d[0] * d[0] + d[1] * d[1] < within * within
                    && (a.arcs[n] - arc()).abs() >= self.layers.exclusion_m
                {
                    out.push(Key {
                        node: [a.owner, n as u32],
                        link: [b.owner, k as u32],
                    });
                }
            }
        }
    }
}

/// Every node and link of two layers whose faces at `pose` are closer than the two sides'
/// margins (`margin[i]` body `i`'s, the laid tape's 0), into `out` in the order of their
/// keys: the features a step measures ([`evaluate`]).
pub(super) fn near(
    chain: &ExactChain,
    pose: &Pose,
    margin: &[f64],
    out: &mut Vec<Key>,
) -> Result<(), StepError> {
    out.clear();
    let Some(layers) = chain.layers.as_ref() else {
        return Ok(());
    };
    let nodes: usize = layers.outlines.iter().map(|o| o.nodes.len()).sum();
    let budget = (FEATURES_PER_NODE * nodes).max(1 << 16);
    let over = |out: &Vec<Key>| {
        (out.len() > budget).then(|| StepError::Unbounded {
            features: out.len(),
            reach_m: margin.iter().copied().fold(0.0, f64::max),
        })
    };
    let bodies = chain.bodies.len();
    let mut search = Search {
        layers,
        world: Vec::new(),
        at: Vec::with_capacity(bodies + 1),
        margin,
        pinned: chain.pin.is_some(),
    };
    let mut boxes: Vec<Aabb> = Vec::with_capacity(bodies);
    for (i, outline) in layers.outlines.iter().enumerate() {
        search.at.push(search.world.len());
        let grow = layers.radius_m + margin[i];
        let mut aabb = [f64::INFINITY, f64::INFINITY, -f64::INFINITY, -f64::INFINITY];
        for &local in &outline.nodes {
            let p = pose.point(i, local);
            aabb = [
                aabb[0].min(p[0] - grow),
                aabb[1].min(p[1] - grow),
                aabb[2].max(p[0] + grow),
                aabb[3].max(p[1] + grow),
            ];
            search.world.push(p);
        }
        boxes.push(aabb);
    }
    search.at.push(search.world.len());
    // Sort and sweep along x: each body against those whose boxes begin before its own
    // and have not ended.
    let mut order: Vec<usize> = (0..bodies).collect();
    order.sort_by(|&a, &b| boxes[a][0].total_cmp(&boxes[b][0]));
    let mut open: Vec<usize> = Vec::new();
    for &i in &order {
        open.retain(|&j| boxes[j][2] >= boxes[i][0]);
        for &j in &open {
            if overlaps(&boxes[i], &boxes[j]) {
                let (a, b) = (search.side(i), search.side(j));
                let (na, nb) = (a.nodes.len(), b.nodes.len());
                search.nodes_on_links((a, 0..na), (b, 0..nb.saturating_sub(1)), out);
                search.nodes_on_links((b, 0..nb), (a, 0..na.saturating_sub(1)), out);
                if let Some(e) = over(out) {
                    return Err(e);
                }
            }
        }
        open.push(i);
    }
    near_laid(chain, &search, &boxes, out, budget);
    if let Some(e) = over(out) {
        return Err(e);
    }
    out.sort_unstable();
    out.dedup();
    Ok(())
}

/// Each body against the laid tape's links its box overlaps, until `out` holds more than
/// `budget` features.
fn near_laid(
    chain: &ExactChain,
    search: &Search<'_>,
    boxes: &[Aabb],
    out: &mut Vec<Key>,
    budget: usize,
) {
    let layers = search.layers;
    let index = &chain.laid_index;
    let laid = &layers.laid;
    if laid.nodes.len() < 2 {
        return;
    }
    let r = layers.radius_m;
    let laid_side = Side {
        owner: LAID,
        nodes: &laid.nodes,
        arcs: &laid.arc_m,
        margin: 0.0,
        first_node: true,
    };
    let last = laid.nodes.len() - 1;
    // The laid tape's last node as a box of its own, for the pin's point (below).
    let [x, y] = laid.nodes[last];
    let pin_box: Aabb = [x, y, x, y];
    for (i, aabb) in boxes.iter().enumerate() {
        // The body's box already holds its own radius and margin: grow it by the laid
        // tape's radius.
        let b = [aabb[0] - r, aabb[1] - r, aabb[2] + r, aabb[3] + r];
        let from = index.left.partition_point(|&x| x < b[0] - index.widest);
        let to = index.left.partition_point(|&x| x <= b[2]);
        let body = search.side(i);
        let n = body.nodes.len();
        // The laid tape's last node, where the first body is pinned, is no laid link's first
        // node, and the pinned body's first node is not its own: a point neither side holds
        // as a node. A body folded back across the pin meets it there.
        if search.pinned && overlaps(&b, &pin_box) {
            search.nodes_on_links(
                (laid_side, last..last + 1),
                (body, 0..n.saturating_sub(1)),
                out,
            );
        }
        for &k in &index.order[from..to] {
            if out.len() > budget {
                return;
            }
            let k = k as usize;
            let (q, s) = (laid.nodes[k], laid.nodes[k + 1]);
            let link_box = [
                q[0].min(s[0]),
                q[1].min(s[1]),
                q[0].max(s[0]),
                q[1].max(s[1]),
            ];
            if !overlaps(&b, &link_box) {
                continue;
            }
            search.nodes_on_links((body, 0..n), (laid_side, k..k + 1), out);
            // The link's first node against the body's links: the laid tape's last node is
            // no link's first, and the first body holds it (it is pinned there).
            search.nodes_on_links((laid_side, k..k + 1), (body, 0..n.saturating_sub(1)), out);
        }
    }
}

/// The layers' touches of the features `keys` at `pose`, in their order, into `out`. A
/// node meets a link where the link's closest point to it is not its last node (which the
/// next link holds), but at the tape's free end. Whether the two are at least
/// [`Layers::exclusion_m`] apart along the tape was decided where `keys` were found, at the
/// step's start ([`near`]): a touch that a fold brings past the exclusion within a step
/// would start to count at whatever depth it has there (links shorter than the thickness
/// always lie within reach of their neighbours), a depth no impulse made and only a move
/// by position could take out, the fold's energy with it. Found at the next step's start,
/// it is a contact at its depth, which the impulses keep from growing.
pub(super) fn evaluate(chain: &ExactChain, pose: &Pose, keys: &[Key], out: &mut Vec<Touch>) {
    out.clear();
    let Some(layers) = chain.layers.as_ref() else {
        return;
    };
    let last_body = chain.bodies.len().saturating_sub(1) as u32;
    let world = |owner: u32, node: u32| -> [f64; 2] {
        if owner == LAID {
            layers.laid.nodes[node as usize]
        } else {
            pose.point(
                owner as usize,
                layers.outlines[owner as usize].nodes[node as usize],
            )
        }
    };
    let arcs = |owner: u32| -> &[f64] {
        if owner == LAID {
            &layers.laid.arc_m
        } else {
            &layers.outlines[owner as usize].arc_m
        }
    };
    for &key in keys {
        let ([a, n], [b, k]) = (key.node, key.link);
        let p = world(a, n);
        let (c, t) = closest_on(p, world(b, k), world(b, k + 1));
        let link_arcs = arcs(b);
        let free_end = b == last_body && k as usize + 2 == link_arcs.len();
        if t >= 1.0 && !free_end {
            continue;
        }
        let d = [p[0] - c[0], p[1] - c[1]];
        let distance = d[0].hypot(d[1]);
        if distance == 0.0 {
            continue;
        }
        let normal = [d[0] / distance, d[1] / distance];
        let gap_m = distance - 2.0 * layers.radius_m;
        let point = [0.5 * (p[0] + c[0]), 0.5 * (p[1] + c[1])];
        // The normal points into a body: the node's, or else the link's.
        out.push(if a != LAID {
            Touch {
                key,
                body: a as usize,
                other: (b != LAID).then_some(b as usize),
                normal,
                gap_m,
                point,
            }
        } else {
            Touch {
                key,
                body: b as usize,
                other: None,
                normal: [-normal[0], -normal[1]],
                gap_m,
                point,
            }
        });
    }
}

/// Keeps of `touches` (a step's, in any order) those that hold each pair of layers: where two
/// rigid pieces, or a piece and the laid tape, lie face to face, a node of each meets the
/// other at many points that hold the same three relative motions, and a direct solve of
/// them all is singular but for its regularisation. Each pair keeps its patch's two ends
/// (along the patch's mean tangent) and its deepest touch, as the floor keeps a piece's hull
/// corners. Left in the order of their keys.
pub(super) fn patches(touches: &mut Vec<Touch>) {
    const LAID_PAIR: usize = usize::MAX;
    touches.sort_by_key(|t| (t.body, t.other.unwrap_or(LAID_PAIR), t.key));
    let mut kept: Vec<Touch> = Vec::with_capacity(touches.len());
    let mut start = 0;
    while start < touches.len() {
        let pair = (touches[start].body, touches[start].other);
        let end = start
            + touches[start..]
                .iter()
                .take_while(|t| (t.body, t.other) == pair)
                .count();
        let group = &touches[start..end];
        if group.len() <= 3 {
            kept.extend_from_slice(group);
        } else {
            let mut normal = [0.0, 0.0];
            for t in group {
                normal = [normal[0] + t.normal[0], normal[1] + t.normal[1]];
            }
            let along = |t: &Touch| t.point[0] * normal[1] - t.point[1] * normal[0];
            let by = |f: &dyn Fn(&Touch) -> f64| {
                (0..group.len())
                    .min_by(|&a, &b| f(&group[a]).total_cmp(&f(&group[b])))
                    .expect("a group is never empty")
            };
            let mut picked = [by(&along), by(&|t| -along(t)), by(&|t| t.gap_m)];
            picked.sort_unstable();
            for (i, &k) in picked.iter().enumerate() {
                if i == 0 || picked[i - 1] != k {
                    kept.push(group[k]);
                }
            }
        }
        start = end;
    }
    kept.sort_by_key(|t| t.key);
    *touches = kept;
}
