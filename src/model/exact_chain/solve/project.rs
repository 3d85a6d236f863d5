//! Moves by position: the bodies moved out of the floor and out of each other where a
//! drift took a contact deeper than the slop ([`project_out`]), and, where the steps are
//! bounded, the joints closed by position at a step's start ([`close_joints`]) and the
//! drift's velocity held to the joints again after a move ([`realign`]).

use super::*;

/// A moved contact's row on one body: the body, its point's Jacobian along the normal, and
/// how far short of its place it is (m).
type OneBody = (usize, [f64; 3], f64);

/// Moves the bodies, not their velocities, out of the floor and out of each other where the
/// drift took a contact deeper than the slop (a point moves on an arc over the step, not on
/// its velocity's line), keeping the joints closed: the mass-weighted least move, by the same
/// block-tridiagonal solve (a contact between two bodies as an auxiliary row against it,
/// `delassus::matrix`), a few times over if the move takes others in; whether it converged.
/// Pushing them out by velocity instead would add their depth over the step to their speed.
pub(super) fn project_out(
    chain: &mut ExactChain,
    s: &mut Scratch,
) -> Result<(bool, bool), StepError> {
    if chain.floor.is_none() && chain.layers.is_none() {
        return Ok((true, false));
    }
    let tol = position_tolerance(chain);
    let deep_by = SLOP * tol;
    let mut deep = Deep::default();
    let mut moved = vec![false; chain.vertices.len()];
    let mut moved_any = false;
    for _ in 0..chain.tolerance.max_iterations {
        let grew = deep.find(chain, s, &mut moved, deep_by);
        if grew {
            deep.floor.sort_by_key(|d| d.0);
        }
        let (rows, pairs) = deep.rows(chain, s);
        let closed =
            rows.iter().all(|r| r.2.abs() <= tol) && pairs.iter().all(|p| p.1.abs() <= tol);
        if closed && s.start_pose.joint_gap(chain) <= tol {
            return Ok((true, moved_any));
        }
        moved_any = true;
        rows::build_projection(chain, s, &rows);
        rows::solve(chain, s)?;
        if pairs.is_empty() {
            move_by_rows(chain, s);
            s.start_pose.take(chain, None);
            continue;
        }
        let mut dq = vec![[0.0; 3]; chain.bodies.len()];
        for (r, &y) in s.rows.iter().zip(&s.x) {
            for a in 0..r.count {
                let (b, d) = (r.body[a], r.d[a]);
                let w = s.inv[b];
                for k in 0..3 {
                    dq[b][k] += w[k] * d[k] * y;
                }
            }
        }
        let dirs: Vec<delassus::Dir> = pairs.iter().map(|p| p.0).collect();
        let w = delassus::matrix(chain, s, &dirs);
        let rhs: Vec<f64> = pairs
            .iter()
            .map(|(dir, miss)| miss - dir.speed(&dq))
            .collect();
        let p = delassus::push_apart(&w, &rhs);
        delassus::respond(chain, s, &dirs, &p, true, &mut dq)?;
        for (body, d) in chain.bodies.iter_mut().zip(&dq) {
            body.position_m[0] += d[0];
            body.position_m[1] += d[1];
            body.angle_rad += d[2];
        }
        s.start_pose.take(chain, None);
    }
    Ok((false, moved_any))
}

/// Closes the joints by position, the velocities kept, where a step starts with one open
/// wider than the position tolerance: a move out of the floor or out of another layer
/// leaves them open within its slop ([`SLOP`] tolerances). The drift would close such a
/// gap by velocity, gap / h, and the kick's energy, as (gap / h)^2, grows as the step
/// shortens: on the thin tape a gap of 50 tolerances (2.5e-11 m) closed over 2e-10 s made
/// the joints' work 7 % of the energy the step moved. Moved instead, the mass-weighted
/// least move of the joints' rows alone (as [`project_out`] moves them), it costs no
/// kinetic energy.
pub(super) fn close_joints(chain: &mut ExactChain, s: &mut Scratch) -> Result<(), StepError> {
    let tol = position_tolerance(chain);
    inverse_masses(chain, s);
    for _ in 0..chain.tolerance.max_iterations {
        s.start_pose.take(chain, None);
        if s.start_pose.joint_gap(chain) <= tol {
            return Ok(());
        }
        rows::build_projection(chain, s, &[]);
        rows::solve(chain, s)?;
        move_by_rows(chain, s);
    }
    Ok(())
}

/// Moves the bodies by the solved projection: each row's multiplier in `s.x` along its
/// directions, weighted by the inverse masses.
fn move_by_rows(chain: &mut ExactChain, s: &Scratch) {
    for (r, &y) in s.rows.iter().zip(&s.x) {
        for a in 0..r.count {
            let (b, d) = (r.body[a], r.d[a]);
            let w = s.inv[b];
            let body = &mut chain.bodies[b];
            body.position_m[0] += w[0] * d[0] * y;
            body.position_m[1] += w[1] * d[1] * y;
            body.angle_rad += w[2] * d[2] * y;
        }
    }
}

/// The drift's velocity held to the joints again where [`project_out`] moved the bodies:
/// a move turns the bodies, and the drift's velocity, which kept every joint's two anchors
/// moving together at the pose the drift reached, no longer does at the moved one. The
/// end's impulses would take that mismatch out whatever the step's length (a piece of the
/// thin tape turned 0.1 rad by a move lost 1 % of the bang's energy so, at any step); it is
/// the move's, not the step's, so it is taken out here and returned apart (J; negative:
/// taken from the chain), with the kick the end's impulses start from recomputed.
pub(super) fn realign(
    chain: &mut ExactChain,
    s: &mut Scratch,
    gravity: [f64; 2],
    h: f64,
) -> Result<f64, StepError> {
    let before = kinetic(chain, &s.drift);
    std::mem::swap(&mut s.free, &mut s.drift);
    delassus::hold(chain, s)?;
    std::mem::swap(&mut s.free, &mut s.drift);
    s.drift.clone_from(&s.v);
    s.free = kicked(&s.drift, gravity, 0.5 * h);
    Ok(kinetic(chain, &s.drift) - before)
}

/// The contacts a projection moves out: once moved, each stays in it until it ends.
#[derive(Default)]
struct Deep {
    /// The floor's: (body, point in its axes, the height it is to be at).
    floor: Vec<(usize, [f64; 2], f64)>,
    /// The layers': each touch's key and the gap it is to be at (its overlap at the step's
    /// start, if any; else 0), by key.
    layers: Vec<(Key, f64)>,
}

impl Deep {
    /// Adds the contacts now deeper than `deep_by` below where they may be; whether a floor
    /// point was added.
    fn find(
        &mut self,
        chain: &ExactChain,
        s: &mut Scratch,
        moved: &mut [bool],
        deep_by: f64,
    ) -> bool {
        let before = self.floor.len();
        if let Some(floor) = chain.floor {
            let r = chain.radius_m();
            // A point the step began with below the floor (the engine's laid tape sits its
            // inset below it) may stay as deep, no deeper.
            for i in 0..chain.bodies.len() {
                let range = chain.vertex_at[i]..chain.vertex_at[i + 1];
                for (v, moved) in range.clone().zip(&mut moved[range]) {
                    let local = chain.vertices[v];
                    let floor_at = s.start_gaps[v].min(0.0);
                    let gap = floor.gap(s.start_pose.point(i, local)) - r;
                    if gap < floor_at - deep_by && !*moved {
                        *moved = true;
                        self.floor.push((i, local, floor_at));
                    }
                }
            }
        }
        if chain.layers.is_some() {
            modes::measure(chain, s);
            let touches = std::mem::take(&mut s.touches);
            for t in &touches {
                let at = s
                    .layer_start_gaps
                    .binary_search_by_key(&t.key, |g| g.0)
                    .map_or(0.0, |i| s.layer_start_gaps[i].1);
                if t.gap_m < at - deep_by
                    && let Err(i) = self.layers.binary_search_by_key(&t.key, |d| d.0)
                {
                    self.layers.insert(i, (t.key, at));
                }
            }
            s.touches = touches;
        }
        self.floor.len() > before
    }

    /// The rows of the moved contacts at `s.start_pose`: those on one body (the floor's, the
    /// laid tape's) as (body, Jacobian, how far short of its place), by body; those between
    /// two bodies as directions with how far short.
    fn rows(
        &self,
        chain: &ExactChain,
        s: &mut Scratch,
    ) -> (Vec<OneBody>, Vec<(delassus::Dir, f64)>) {
        let mut one: Vec<OneBody> = Vec::new();
        let mut two = Vec::new();
        if let Some(floor) = chain.floor {
            let r = chain.radius_m();
            for &(i, local, at) in &self.floor {
                let a = s.start_pose.arm(i, local);
                let gap = floor.gap(s.start_pose.point(i, local)) - r;
                one.push((i, rows::along(floor.normal, a), at - gap));
            }
        }
        if !self.layers.is_empty() {
            modes::measure(chain, s);
            let touches = std::mem::take(&mut s.touches);
            for t in &touches {
                let Ok(i) = self.layers.binary_search_by_key(&t.key, |d| d.0) else {
                    continue;
                };
                let at = self.layers[i].1;
                let offset = |b: usize| {
                    let c = s.start_pose.centre(b);
                    [t.point[0] - c[0], t.point[1] - c[1]]
                };
                let d = rows::along(t.normal, offset(t.body));
                match t.other {
                    None => one.push((t.body, d, at - t.gap_m)),
                    Some(o) => {
                        let back = rows::along([-t.normal[0], -t.normal[1]], offset(o));
                        let dir = delassus::Dir {
                            body: t.body,
                            d,
                            other: Some((o, back)),
                        };
                        two.push((dir, at - t.gap_m));
                    }
                }
            }
            s.touches = touches;
        }
        one.sort_by_key(|r| r.0);
        (one, two)
    }
}
