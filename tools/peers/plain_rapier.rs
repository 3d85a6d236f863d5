//! The yoga mat as a plain rapier2d chain, the way a careful user would write it without
//! uncoil's model: every link a rigid body with a cuboid collider, neighbours joined by
//! impulse joints, a frictional floor, one fixed time step, every link in the engine from
//! start to end. It is a peer for docs/peers.md; it borrows from the `uncoil` crate only the
//! scene, the spiral geometry and the exact-geometry reference, never its model (no
//! freezing, no adaptive step, no wound coil as one body).
//!
//! A chain of free hinges does not stay wound: held only by contact between its turns
//! (`--hold contacts`) the coil slumps and stops within a few centimetres. So by default
//! (`--hold locks`) each joint is locked at its spiral angle until its node reaches the
//! floor, where the tape peels off the coil, and is a free hinge from then on: the rigid
//! coil the exact-geometry model assumes, made of joints the solver has to hold.
//!
//! `cargo run --release --example plain-rapier -- --help` lists the settings. The last
//! line printed is one JSON object for tools/peers/compare.py.

use std::f64::consts::PI;
use std::path::PathBuf;
use std::time::Instant;

use clap::Parser;
use rapier2d_f64::prelude::*;
use uncoil::scene::Scene;
use uncoil::spiral::{Spiral, SpiralMoments, rotate};
use uncoil::theory::exact_geometry;

/// Laid fractions the run is timed at: 0.75R (f = 0.4375, uncoil's first milestone), 0.5R
/// (0.75) and 0.9.
const MILESTONES: [f64; 3] = [0.4375, 0.75, 0.9];

/// A collider's `user_data` that marks the floor (links carry their index).
const FLOOR_TAG: u128 = u128::MAX;

/// What keeps the wound turns in their spiral.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
enum Hold {
    /// Each joint locked until its node reaches the floor; links touch only the floor.
    Locks,
    /// Free hinges; links at least three quarters of a turn apart touch each other.
    Contacts,
}

#[derive(Parser, Debug)]
#[command(about = "The yoga mat as a plain rapier2d chain of hinged cuboids")]
struct Args {
    /// Scene file (default: the repository's scenes/yoga-mat.toml).
    #[arg(long)]
    scene: Option<PathBuf>,
    /// Fixed time step (s).
    #[arg(long, default_value_t = 2.0e-4)]
    dt_s: f64,
    /// Solver iterations per step (rapier's substeps, `num_solver_iterations`; rapier's
    /// default is 4, under which the 351 locked joints bend like a spring).
    #[arg(long, default_value_t = 32)]
    iterations: usize,
    /// Gauss-Seidel sweeps per solver iteration (rapier's `num_internal_pgs_iterations`).
    #[arg(long, default_value_t = 1)]
    pgs: usize,
    /// Warm-start the joints with the last step's impulses (rapier's `warmstart_joints`).
    #[arg(long)]
    warmstart_joints: bool,
    /// Links per turn of the spiral (default: the scene's).
    #[arg(long)]
    links_per_turn: Option<u32>,
    /// Natural frequency of every contact, floor and layer-on-layer (Hz). Rapier's defaults,
    /// 30 between bodies and 60 on the floor, let the coil sink 69 um into the floor and,
    /// held by contacts, slump.
    #[arg(long, default_value_t = 1.0e4)]
    contact_hz: f64,
    /// Natural frequency of the joints (Hz; default: rapier's, 1e6).
    #[arg(long)]
    joint_hz: Option<f64>,
    /// Rapier's `length_unit` (m), which scales its tolerances: the prediction distance is
    /// 0.02 of it, so at rapier's 1 m every link of the 12 cm coil would be a contact
    /// candidate of every other (default: the tape's thickness).
    #[arg(long)]
    length_unit_m: Option<f64>,
    /// Print time, laid fraction and energy every this many steps (0: never).
    #[arg(long, default_value_t = 0)]
    trace: u64,
    /// What keeps the wound turns in their spiral.
    #[arg(long, value_enum, default_value_t = Hold::Locks)]
    hold: Hold,
    /// A locked joint is freed once its node is this close to the laid midline height (m;
    /// default: b / 100).
    #[arg(long)]
    release_m: Option<f64>,
    /// Round each link's ends: a capsule (radius half the collider thickness) instead of a
    /// cuboid. The coil's outline is then smooth, but a landing link still moves the pivot
    /// from one of its ends to the other: an impact all the same (docs/peers.md).
    #[arg(long)]
    capsules: bool,
    /// Thickness of the links' colliders (m; default: the tape's, b). The floor is put at
    /// half of it below the laid midline (b/2): a thinner collider rolls the coil closer
    /// to its midline, as the exact model does.
    #[arg(long)]
    collider_thickness_m: Option<f64>,
    /// Give each link the cuboid's own moment of inertia, m (l^2 + b^2) / 12, rather than a
    /// rod's, m l^2 / 12 (the exact model's line mass).
    #[arg(long)]
    cuboid_inertia: bool,
    /// Stop once this fraction of the tape is laid.
    #[arg(long, default_value_t = 0.9)]
    stop_fraction: f64,
}

/// One link: a chord of the spiral between two nodes, and its body.
struct Link {
    body: RigidBodyHandle,
    /// Direction of the chord (near node -> far node) in the spiral's frame (rad).
    angle_rad: f64,
    mass_kg: f64,
    inertia_kg_m2: f64,
}

/// Contacts only between links at least three quarters of a turn apart along the tape:
/// neighbouring layers touch, a link and its neighbours in the same layer (which overlap
/// where the tape bends, and near the centre span the whole turn) do not.
struct LayerFilter {
    min_gap: u128,
}

impl PhysicsHooks for LayerFilter {
    fn filter_contact_pair(&self, ctx: &PairFilterContext) -> Option<SolverFlags> {
        let i = ctx.colliders[ctx.collider1].user_data;
        let j = ctx.colliders[ctx.collider2].user_data;
        let touches = i == FLOOR_TAG || j == FLOOR_TAG || i.abs_diff(j) >= self.min_gap;
        touches.then_some(SolverFlags::COMPUTE_RIGID_IMPULSES)
    }
}

/// Wraps an angle into (-pi, pi].
fn wrap(a: f64) -> f64 {
    a - (a / (2.0 * PI)).round() * 2.0 * PI
}

fn main() -> anyhow::Result<()> {
    let started = Instant::now();
    let args = Args::parse();
    let path = args
        .scene
        .clone()
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes/yoga-mat.toml"));
    let scene = Scene::from_file(&path)?;
    let exact = exact_geometry(&scene);
    let (big_r, b, big_m) = (
        scene.tape.outer_radius_m,
        scene.tape.thickness_m,
        scene.tape.mass_kg,
    );
    let g = scene.gravity.g_m_s2;
    let lpt = args
        .links_per_turn
        .unwrap_or(scene.discretisation.links_per_turn);

    // The midline and its nodes, as uncoil places them: equal angles per turn from the outer
    // end inward, the outer end at the bottom of the coil, on the floor at x = 0.
    let spiral = Spiral::wound(big_r, b, scene.tape.core_radius_m);
    let moments = SpiralMoments::new(spiral);
    let length_m = spiral.length();
    let nodes = spiral.link_nodes(lpt);
    let rot0 = spiral.rotation_with_bottom_at(spiral.psi_out);
    let low = rotate(spiral.point(spiral.psi_out), rot0);
    // Laid tape has its midline at y = b/2, the floor half a collider thickness below
    // (y = 0 for colliders b thick).
    let contact = [0.0, 0.5 * b];
    let origin = [contact[0] - low[0], contact[1] - low[1]];
    let world_node = |psi: f64| {
        let p = rotate(spiral.point(psi), rot0);
        [origin[0] + p[0], origin[1] + p[1]]
    };
    // Rolling without slip about the contact at the push speed: the exact model's start,
    // omega = v / (radius of curvature at the outer end), clockwise.
    let omega = -scene.push.contact_speed_m_s / spiral.curvature_radius(spiral.psi_out);

    let mut world = PhysicsWorld::new();
    world.gravity = Vector::new(0.0, -g);
    let ip = &mut world.integration_parameters;
    ip.dt = args.dt_s;
    ip.num_solver_iterations = args.iterations;
    ip.num_internal_pgs_iterations = args.pgs;
    ip.warmstart_joints = args.warmstart_joints;
    ip.length_unit = args.length_unit_m.unwrap_or(b);
    let soft = SpringCoefficients::new(args.contact_hz, ip.contact_softness.damping_ratio);
    ip.contact_softness = soft;
    ip.static_contact_softness = soft;
    let half_t_m = 0.5 * args.collider_thickness_m.unwrap_or(b);
    let ground = world.insert_body(RigidBodyBuilder::fixed());
    world.insert_collider(
        ColliderBuilder::new(SharedShape::halfspace(Vector::Y))
            .translation(Vector::new(0.0, 0.5 * b - half_t_m))
            .friction(scene.floor.friction)
            .user_data(FLOOR_TAG)
            .collision_groups(InteractionGroups::new(
                Group::GROUP_2,
                Group::GROUP_1,
                InteractionTestMode::And,
            )),
        Some(ground),
    );
    // Held by locks, links meet only the floor; held by contacts, also each other, as the
    // hooks allow.
    let tape_filter = match args.hold {
        Hold::Locks => Group::GROUP_2,
        Hold::Contacts => Group::GROUP_1 | Group::GROUP_2,
    };
    let joint_axes = match args.hold {
        Hold::Locks => JointAxesMask::LOCKED_FIXED_AXES,
        Hold::Contacts => JointAxesMask::LOCKED_REVOLUTE_AXES,
    };

    let chords: Vec<f64> = nodes
        .windows(2)
        .map(|w| {
            let (p, q) = (spiral.point(w[0]), spiral.point(w[1]));
            (q[0] - p[0]).hypot(q[1] - p[1])
        })
        .collect();
    let total_chord: f64 = chords.iter().sum();
    let mut links = Vec::with_capacity(chords.len());
    // joints[k] joins links k and k + 1 at node k + 1.
    let mut joints = Vec::with_capacity(chords.len());
    for (k, w) in nodes.windows(2).enumerate() {
        let (near, far) = (world_node(w[0]), world_node(w[1]));
        let (len, angle) = (chords[k], (far[1] - near[1]).atan2(far[0] - near[0]));
        let centre = [0.5 * (near[0] + far[0]), 0.5 * (near[1] + far[1])];
        // The exact model's tape is a line mass on the midline: mass by length and a rod's
        // inertia, not the cuboid's (its thickness would add M b^2 / 12 to the coil).
        let mass_kg = big_m * len / total_chord;
        let inertia_kg_m2 = if args.cuboid_inertia {
            mass_kg * (len * len + b * b) / 12.0
        } else {
            mass_kg * len * len / 12.0
        };
        let rel = [centre[0] - contact[0], centre[1] - contact[1]];
        let body = world.insert_body(
            RigidBodyBuilder::dynamic()
                .pose(Pose::new(Vector::new(centre[0], centre[1]), angle))
                .additional_mass_properties(MassProperties::new(
                    Vector::ZERO,
                    mass_kg,
                    inertia_kg_m2,
                ))
                .linvel(Vector::new(-omega * rel[1], omega * rel[0]))
                .angvel(omega)
                .can_sleep(false),
        );
        world.insert_collider(
            if args.capsules {
                ColliderBuilder::capsule_x(0.5 * len, half_t_m)
            } else {
                ColliderBuilder::cuboid(0.5 * len, half_t_m)
            }
            .density(0.0)
            .friction(scene.floor.friction)
            .user_data(k as u128)
            .collision_groups(InteractionGroups::new(
                Group::GROUP_1,
                tape_filter,
                InteractionTestMode::And,
            ))
            .active_hooks(ActiveHooks::FILTER_CONTACT_PAIRS),
            Some(body),
        );
        if let Some(prev) = links.last() {
            let prev: &Link = prev;
            // The joint's frames at the shared node, turned so that the spiral's angle
            // between the two links is the locked one.
            let mut joint = GenericJointBuilder::new(joint_axes)
                .local_frame1(Pose::new(Vector::new(0.5 * chords[k - 1], 0.0), 0.0))
                .local_frame2(Pose::new(
                    Vector::new(-0.5 * len, 0.0),
                    prev.angle_rad + rot0 - angle,
                ))
                .contacts_enabled(false);
            if let Some(hz) = args.joint_hz {
                joint = joint.softness(SpringCoefficients::new(hz, 1.0));
            }
            joints.push(world.insert_impulse_joint(prev.body, body, joint));
        }
        links.push(Link {
            body,
            angle_rad: angle - rot0,
            mass_kg,
            inertia_kg_m2,
        });
    }
    let hooks = LayerFilter {
        min_gap: u128::from(lpt * 3 / 4),
    };

    // Energy above the tape lying flat (midline at b/2), kinetic + potential (J).
    let energy = |world: &PhysicsWorld| -> f64 {
        links
            .iter()
            .map(|l| {
                let body = &world.bodies[l.body];
                let w = body.angvel();
                0.5 * l.mass_kg * body.linvel().length_squared()
                    + 0.5 * l.inertia_kg_m2 * w * w
                    + l.mass_kg * g * (body.translation().y - 0.5 * b)
            })
            .sum()
    };
    let e0_j = energy(&world);

    // The laid fraction, measured as uncoil measures its coil's: where the lowest point of
    // the wound spiral is. The wound links keep their angles in the spiral's frame, so
    // their world angles give the coil's rotation, and the rotation the spiral parameter
    // whose tangent is horizontal (Spiral::lowest_psi).
    let quarter = (lpt as usize / 4).max(2);
    let threshold_rad = 0.5 * 2.0 * PI / f64::from(lpt);
    // Read by the trace too, hence a Cell.
    let first_wound = std::cell::Cell::new(0usize);
    let mut psi_low = spiral.psi_out;
    let mut laid = |world: &PhysicsWorld| -> f64 {
        let turned =
            |k: usize| wrap(world.bodies[links[k].body].rotation().angle()) > threshold_rad;
        let mut k = first_wound.get().saturating_sub(2);
        while k + 1 < links.len() && !turned(k) {
            k += 1;
        }
        first_wound.set(k);
        let span = (k + 1)..(k + 1 + quarter).min(links.len());
        if span.is_empty() {
            return 1.0;
        }
        let angle_of =
            |j: usize| world.bodies[links[j].body].rotation().angle() - links[j].angle_rad;
        let reference = angle_of(span.start);
        let n = span.len() as f64;
        let rotation = reference + span.map(|j| wrap(angle_of(j) - reference)).sum::<f64>() / n;
        psi_low = spiral
            .lowest_psi(rotation, psi_low)
            .clamp(spiral.psi_in, spiral.psi_out);
        1.0 - moments.length_at(psi_low) / length_m
    };

    let t_exact: Vec<Option<f64>> = MILESTONES
        .iter()
        .map(|&f| exact.time_at_fraction(f))
        .collect();
    let t_limit_s = 3.0 * t_exact.iter().flatten().fold(1.0, |a: f64, &t| a.max(t));
    // The next locked joint, counted from the outer end; they reach the floor in order.
    let mut next_lock = if args.hold == Hold::Locks {
        0
    } else {
        joints.len()
    };
    let release_m = args.release_m.unwrap_or(0.01 * b);
    let mut hits: Vec<Option<(f64, f64)>> = vec![None; MILESTONES.len()];
    let (mut t_s, mut f_prev, mut e_prev) = (0.0, laid(&world), e0_j);
    let (mut steps, mut stepping_s, mut max_gain_j) = (0u64, 0.0, 0.0f64);
    // The best laid fraction so far and when it was reached: no progress in a second of
    // simulated time is a stall.
    let (mut f_best, mut t_best) = (f_prev, 0.0);
    let outcome = loop {
        let tick = Instant::now();
        world.step_with_events(&hooks, &());
        stepping_s += tick.elapsed().as_secs_f64();
        steps += 1;
        t_s += args.dt_s;
        // Free the joints whose node has reached the floor: the tape peels off there.
        while next_lock < joints.len() {
            let body = &world.bodies[links[next_lock].body];
            let node = body
                .position()
                .transform_point(Vector::new(0.5 * chords[next_lock], 0.0));
            if node.y > 0.5 * b + release_m {
                break;
            }
            if let Some(joint) = world.impulse_joints.get_mut(joints[next_lock], false) {
                joint.data.locked_axes = JointAxesMask::LOCKED_REVOLUTE_AXES;
            }
            next_lock += 1;
        }
        let (f, e) = (laid(&world), energy(&world));
        max_gain_j = max_gain_j.max(e - e0_j);
        for (k, &target) in MILESTONES.iter().enumerate() {
            if hits[k].is_none() && f_prev < target && f >= target {
                let s = (target - f_prev) / (f - f_prev);
                hits[k] = Some((t_s - args.dt_s * (1.0 - s), e_prev + s * (e - e_prev)));
            }
        }
        if args.trace > 0 && steps % args.trace == 0 {
            let y: Vec<String> = [0, links.len() / 2, links.len() - 1]
                .iter()
                .map(|&k| format!("{:.4}", world.bodies[links[k].body].translation().y))
                .collect();
            eprintln!(
                "t {t_s:.4} f {f:.5} E {e:.5} first_wound {} y {y:?}",
                first_wound.get()
            );
        }
        (f_prev, e_prev) = (f, e);
        if f > f_best + 1e-3 {
            (f_best, t_best) = (f, t_s);
        }
        if !e.is_finite() || e > 2.0 * e0_j {
            break format!("exploded at t = {t_s:.4} s (energy {:.3} of E0)", e / e0_j);
        }
        if f >= args.stop_fraction {
            break "completed".to_string();
        }
        if t_s - t_best > 1.0 || t_s > t_limit_s {
            break format!("stalled at laid fraction {f_best:.4} (t = {t_best:.4} s)");
        }
    };

    let wall_s = started.elapsed().as_secs_f64();
    println!(
        "plain-rapier: {} links ({lpt} per turn), dt {} s, {} iterations, {steps} steps, {t_s:.4} s simulated",
        links.len(),
        args.dt_s,
        args.iterations
    );
    println!("  wall {wall_s:.3} s (stepping {stepping_s:.3} s); {outcome}");
    println!(
        "  E0 = {e0_j:.5} J above flat; largest rise above E0 {:.3} % of E0",
        100.0 * max_gain_j / e0_j
    );
    let mut rows = Vec::new();
    for (k, &f) in MILESTONES.iter().enumerate() {
        let exact_s = t_exact[k];
        let row = match (hits[k], exact_s) {
            (Some((t, e)), Some(te)) => {
                let (err, lost) = (100.0 * (t - te) / te, 100.0 * (e0_j - e) / e0_j);
                println!(
                    "  f = {f:.4}: t {t:.4} s, exact {te:.4} s, error {err:+.3} %, energy lost {lost:.3} % of E0"
                );
                serde_json::json!({"f": f, "t_s": t, "exact_s": te, "error_pct": err, "lost_pct": lost})
            }
            _ => {
                println!("  f = {f:.4}: not reached");
                serde_json::json!({"f": f, "t_s": null, "exact_s": exact_s, "error_pct": null, "lost_pct": null})
            }
        };
        rows.push(row);
    }
    let json = serde_json::json!({
        "peer": "plain-rapier",
        "settings": {"dt_s": args.dt_s, "iterations": args.iterations, "links_per_turn": lpt,
                     "contact_hz": args.contact_hz, "joint_hz": args.joint_hz,
                     "hold": format!("{:?}", args.hold), "pgs": args.pgs, "warmstart_joints": args.warmstart_joints, "capsules": args.capsules, "collider_thickness_m": 2.0 * half_t_m,
                     "cuboid_inertia": args.cuboid_inertia},
        "links": links.len(), "steps": steps, "sim_s": t_s,
        "wall_s": wall_s, "stepping_s": stepping_s, "outcome": outcome,
        "e0_j": e0_j, "max_gain_pct": 100.0 * max_gain_j / e0_j, "milestones": rows,
    });
    println!("{json}");
    Ok(())
}
