//! Where a polyline crosses itself, and how close it comes to itself: the tape's drawn
//! midline in the final bang, read back from `run.mcap` by [`crate::output::inspect`] and
//! by `uncoil plot`'s `bang.svg`.
//! Pure `f64` plane geometry; it knows nothing of tapes or files.
//!
//! Segment `i` joins points `i` and `i + 1`. Two segments cross when they are not
//! neighbours (`j >= i + 2`) and intersect properly: each one's ends lie strictly on
//! opposite sides of the other's line. So segments that only touch (an end on the other,
//! a shared point, collinear overlap) do not count, and neither do neighbours, which share
//! a point by construction. The pairs are found by a sweep along x over the segments'
//! boxes: linear in the segments where the line is spread out, as a laid tape is.

/// What [`self_contact`] finds on one polyline.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SelfContact {
    /// Pairs of segments that cross.
    pub crossings: usize,
    /// The least distance between two segments at least `apart` from each other along
    /// the line (from the end of the one to the start of the other), if any pair comes
    /// within `near` of each other (0 where they cross).
    pub closest_m: Option<f64>,
}

fn sub(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    [a[0] - b[0], a[1] - b[1]]
}

fn cross(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

/// Twice the signed area of the triangle `a b c`: positive when `c` is left of `a -> b`.
fn orient(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    cross(sub(b, a), sub(c, a))
}

/// Whether segments `p0 p1` and `q0 q1` intersect properly: each one's ends strictly on
/// opposite sides of the other's line.
pub fn properly_intersect(p: [[f64; 2]; 2], q: [[f64; 2]; 2]) -> bool {
    let d1 = orient(q[0], q[1], p[0]);
    let d2 = orient(q[0], q[1], p[1]);
    let d3 = orient(p[0], p[1], q[0]);
    let d4 = orient(p[0], p[1], q[1]);
    d1 * d2 < 0.0 && d3 * d4 < 0.0
}

/// The distance from `c` to the segment `a b`.
fn point_segment(c: [f64; 2], [a, b]: [[f64; 2]; 2]) -> f64 {
    let ab = sub(b, a);
    let len2 = ab[0] * ab[0] + ab[1] * ab[1];
    let s = if len2 > 0.0 {
        ((c[0] - a[0]) * ab[0] + (c[1] - a[1]) * ab[1]) / len2
    } else {
        0.0
    };
    let s = s.clamp(0.0, 1.0);
    let d = sub(c, [a[0] + s * ab[0], a[1] + s * ab[1]]);
    d[0].hypot(d[1])
}

/// The distance between segments `p` and `q`: 0 where they intersect properly, else the
/// least of their ends' distances to the other.
pub fn segment_distance(p: [[f64; 2]; 2], q: [[f64; 2]; 2]) -> f64 {
    if properly_intersect(p, q) {
        return 0.0;
    }
    point_segment(p[0], q)
        .min(point_segment(p[1], q))
        .min(point_segment(q[0], p))
        .min(point_segment(q[1], p))
}

/// The pairs of segments `i < j` of `points` whose boxes, each widened by `margin_m`,
/// overlap, with `j >= i + 2`: a sweep along x.
fn near_pairs(points: &[[f64; 2]], margin_m: f64) -> Vec<(usize, usize)> {
    let n = points.len().saturating_sub(1);
    let boxes: Vec<[f64; 4]> = (0..n)
        .map(|i| {
            let (a, b) = (points[i], points[i + 1]);
            [
                a[0].min(b[0]) - margin_m,
                a[1].min(b[1]) - margin_m,
                a[0].max(b[0]) + margin_m,
                a[1].max(b[1]) + margin_m,
            ]
        })
        .collect();
    let mut order: Vec<usize> = (0..n).filter(|&i| boxes[i][0].is_finite()).collect();
    order.sort_by(|&a, &b| boxes[a][0].total_cmp(&boxes[b][0]));
    let mut active: Vec<usize> = Vec::new();
    let mut pairs = Vec::new();
    for &i in &order {
        let bi = boxes[i];
        active.retain(|&j| boxes[j][2] >= bi[0]);
        for &j in &active {
            let bj = boxes[j];
            if i.abs_diff(j) >= 2 && bj[1] <= bi[3] && bi[1] <= bj[3] {
                pairs.push((i.min(j), i.max(j)));
            }
        }
        active.push(i);
    }
    pairs
}

/// The segments of `points` that cross (see the module's rule), as pairs `i < j`.
pub fn crossing_pairs(points: &[[f64; 2]]) -> Vec<(usize, usize)> {
    let seg = |i: usize| [points[i], points[i + 1]];
    let mut pairs: Vec<(usize, usize)> = near_pairs(points, 0.0)
        .into_iter()
        .filter(|&(i, j)| properly_intersect(seg(i), seg(j)))
        .collect();
    pairs.sort_unstable();
    pairs
}

/// Where the segments of `points` cross (see the module's rule): each crossing's point, in
/// the order of [`crossing_pairs`].
pub fn crossing_points(points: &[[f64; 2]]) -> Vec<[f64; 2]> {
    crossing_pairs(points)
        .into_iter()
        .map(|(i, j)| {
            let (p, q) = (points[i], points[j]);
            let (r, s) = (sub(points[i + 1], p), sub(points[j + 1], q));
            // p + u r = q + v s; a proper intersection has r x s != 0.
            let u = cross(sub(q, p), s) / cross(r, s);
            [p[0] + u * r[0], p[1] + u * r[1]]
        })
        .collect()
}

/// How `points` meets itself: the pairs of segments that cross, and the least distance
/// between two segments at least `apart_m` apart along the line, where it is below
/// `near_m`.
pub fn self_contact(points: &[[f64; 2]], near_m: f64, apart_m: f64) -> SelfContact {
    let seg = |i: usize| [points[i], points[i + 1]];
    // Arc length at each point.
    let mut s = Vec::with_capacity(points.len());
    let mut total = 0.0;
    for (k, p) in points.iter().enumerate() {
        if k > 0 {
            let d = sub(*p, points[k - 1]);
            total += d[0].hypot(d[1]);
        }
        s.push(total);
    }
    let mut crossings = 0;
    let mut closest: Option<f64> = None;
    for (i, j) in near_pairs(points, near_m) {
        let (p, q) = (seg(i), seg(j));
        let crossed = properly_intersect(p, q);
        crossings += usize::from(crossed);
        if s[j] - s[i + 1] >= apart_m {
            let d = if crossed { 0.0 } else { segment_distance(p, q) };
            if d < near_m && closest.is_none_or(|c| d < c) {
                closest = Some(d);
            }
        }
    }
    SelfContact {
        crossings,
        closest_m: closest,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    /// A figure eight: a lemniscate of Gerono, closed, crossing itself once at the origin.
    fn figure_eight(n: usize) -> Vec<[f64; 2]> {
        // Start off the crossing point, so that no vertex lies on it.
        (0..=n)
            .map(|k| {
                let t = 0.1 + 2.0 * PI * k as f64 / n as f64;
                [t.sin(), t.sin() * t.cos()]
            })
            .collect()
    }

    /// An Archimedean spiral of pitch `b` from radius `b` out over `turns`.
    fn spiral(b: f64, turns: f64, per_turn: usize) -> Vec<[f64; 2]> {
        let n = (turns * per_turn as f64) as usize;
        (0..=n)
            .map(|k| {
                let phi = 2.0 * PI * k as f64 / per_turn as f64;
                let r = b + b * phi / (2.0 * PI);
                [r * phi.cos(), r * phi.sin()]
            })
            .collect()
    }

    #[test]
    fn a_figure_eight_crosses_once() {
        let eight = figure_eight(101);
        assert_eq!(
            crossing_pairs(&eight).len(),
            1,
            "{:?}",
            crossing_pairs(&eight)
        );
        assert_eq!(self_contact(&eight, 0.1, 0.5).crossings, 1);
        assert_eq!(self_contact(&eight, 0.1, 0.5).closest_m, Some(0.0));
        // It crosses at the origin, to the chords' sag.
        let [at] = crossing_points(&eight)[..] else {
            panic!("one crossing");
        };
        assert!(at[0].abs() < 1e-3 && at[1].abs() < 1e-3, "{at:?}");
    }

    #[test]
    fn a_spiral_does_not_cross_and_comes_within_its_pitch() {
        let b = 0.005;
        let line = spiral(b, 4.0, 32);
        assert!(crossing_pairs(&line).is_empty());
        let c = self_contact(&line, 1.5 * b, PI * b);
        assert_eq!(c.crossings, 0);
        // Neighbouring turns are one pitch apart, less the chords' sag (under 2 %).
        let closest = c.closest_m.expect("turns within 1.5 b");
        assert!(closest > 0.97 * b && closest < 1.01 * b, "{closest}");
        // Nothing within a tenth of the pitch.
        assert_eq!(self_contact(&line, 0.1 * b, PI * b).closest_m, None);
    }

    #[test]
    fn touching_and_neighbouring_segments_do_not_count() {
        // A zigzag: each segment touches its neighbours only.
        let zigzag: Vec<[f64; 2]> = (0..20)
            .map(|k| [k as f64, if k % 2 == 0 { 0.0 } else { 1.0 }])
            .collect();
        assert!(crossing_pairs(&zigzag).is_empty());
        // A line folded back onto a vertex of itself: it touches there, crosses nowhere.
        let touch = [
            [0.0, 0.0],
            [2.0, 0.0],
            [4.0, 0.0],
            [3.0, 1.0],
            [2.0, 0.0],
            [1.0, -1.0],
        ];
        assert!(crossing_pairs(&touch).is_empty());
        // A line doubling back along itself: collinear overlap is no crossing.
        let back = [[0.0, 0.0], [3.0, 0.0], [3.0, 1.0], [1.0, 0.0], [-1.0, 0.0]];
        assert!(crossing_pairs(&back).is_empty());
        // But a loop through a segment is one.
        let through = [[0.0, 0.0], [4.0, 0.0], [4.0, 1.0], [2.0, 1.0], [2.0, -1.0]];
        assert_eq!(crossing_pairs(&through), [(0, 3)]);
    }

    #[test]
    fn the_sweep_finds_what_every_pair_finds() {
        // A tangled line of pseudo-random steps against the test of every pair.
        let mut x: u64 = 0x9e37_79b9_7f4a_7c15;
        let mut p = [0.0_f64, 0.0];
        let mut line = vec![p];
        for _ in 0..300 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let a = (x % 6283) as f64 / 1000.0;
            p = [p[0] + a.cos(), p[1] + a.sin()];
            line.push(p);
        }
        let mut every = Vec::new();
        for i in 0..line.len() - 1 {
            for j in i + 2..line.len() - 1 {
                if properly_intersect([line[i], line[i + 1]], [line[j], line[j + 1]]) {
                    every.push((i, j));
                }
            }
        }
        assert!(every.len() > 10);
        assert_eq!(crossing_pairs(&line), every);
        assert_eq!(self_contact(&line, 0.5, 3.0).crossings, every.len());
    }

    #[test]
    fn segment_distance_is_zero_across_and_the_gap_apart() {
        let p = [[0.0, 0.0], [2.0, 0.0]];
        assert_eq!(segment_distance(p, [[1.0, -1.0], [1.0, 1.0]]), 0.0);
        assert!((segment_distance(p, [[1.0, 0.5], [1.0, 2.0]]) - 0.5).abs() < 1e-15);
        assert!((segment_distance(p, [[3.0, 4.0], [5.0, 4.0]]) - 17.0_f64.sqrt()).abs() < 1e-15);
    }
}
