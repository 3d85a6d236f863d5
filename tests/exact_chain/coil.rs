//! A wound coil with a thickness on the exact chain, built the same way for the property
//! tests (`tests/exact_chain.rs`) and the step's benchmark (`benches/step.rs`, which
//! includes this file by its path).

use uncoil::model::exact_chain::{
    Body, ExactChain, Floor, Joint, Layers, Outline, Tolerance, hull_corners,
};

/// A coil with a thickness as the property draws it: rigid pieces of `links` links each,
/// wound on an Archimedean spiral whose turns are one thickness apart from an innermost
/// midline radius of half a thickness (a coreless coil's), spinning and moving as one.
#[derive(Debug, Clone)]
pub struct Coil {
    /// Rigid pieces, joined end to end.
    pub pieces: usize,
    /// Links of each piece, half a thickness long each.
    pub links: usize,
    /// The tape's thickness b (m).
    pub thickness_m: f64,
    /// The coil's spin as one body (rad/s, counterclockwise positive).
    pub spin_rad_s: f64,
    /// Its centre's velocity (m/s).
    pub velocity_m_s: [f64; 2],
    /// The floor's slope (rad); gravity stays vertical.
    pub slope: f64,
    /// Coulomb's coefficient on the floor.
    pub friction: f64,
    /// Coulomb's coefficient between layers.
    pub self_friction: f64,
    /// The step's turn of the fastest piece (rad): the step is this over the spin.
    pub turn: f64,
}

/// The chain of `c`: links half a thickness long, the tape 0.5 kg/m, the coil's lowest
/// face on the floor.
pub fn coil_chain(c: &Coil) -> ExactChain {
    let b = c.thickness_m;
    let (link, lambda) = (0.5 * b, 0.5);
    // Nodes along r = b/2 + b theta / (2 pi), a link's length apart, from the inner end.
    let count = c.pieces * c.links + 1;
    let mut nodes = Vec::with_capacity(count);
    let (mut theta, mut arc) = (0.0_f64, Vec::with_capacity(count));
    let at = |t: f64| {
        let r = 0.5 * b + b * t / std::f64::consts::TAU;
        [r * t.cos(), r * t.sin()]
    };
    nodes.push(at(0.0));
    arc.push(0.0);
    while nodes.len() < count {
        let last = *nodes.last().unwrap();
        let r = 0.5 * b + b * theta / std::f64::consts::TAU;
        let mut t = theta + link / r.max(0.5 * b);
        for _ in 0..40 {
            let p = at(t);
            let d = (p[0] - last[0]).hypot(p[1] - last[1]);
            t += (link - d) / r.max(0.5 * b);
        }
        theta = t;
        nodes.push(at(t));
        arc.push(arc.last().unwrap() + link);
    }
    let outer = 0.5 * b + b * theta / std::f64::consts::TAU;
    // The floor's line through the coil's lowest face, along the slope.
    let normal = [-c.slope.sin(), c.slope.cos()];
    let lowest = nodes
        .iter()
        .map(|p| p[0] * normal[0] + p[1] * normal[1])
        .fold(f64::MAX, f64::min);
    let floor_point = [
        (lowest - 0.5 * b) * normal[0],
        (lowest - 0.5 * b) * normal[1],
    ];
    let mut bodies = Vec::with_capacity(c.pieces);
    let mut outlines = Vec::with_capacity(c.pieces);
    let mut points = Vec::with_capacity(c.pieces);
    for p in 0..c.pieces {
        let own = &nodes[p * c.links..=(p + 1) * c.links];
        let m = lambda * link;
        let mids: Vec<[f64; 2]> = own
            .windows(2)
            .map(|w| [0.5 * (w[0][0] + w[1][0]), 0.5 * (w[0][1] + w[1][1])])
            .collect();
        let k = mids.len() as f64;
        let centre = [
            mids.iter().map(|q| q[0]).sum::<f64>() / k,
            mids.iter().map(|q| q[1]).sum::<f64>() / k,
        ];
        let inertia = mids
            .iter()
            .map(|q| {
                m * ((link * link + b * b) / 12.0
                    + (q[0] - centre[0]).powi(2)
                    + (q[1] - centre[1]).powi(2))
            })
            .sum::<f64>();
        let w = c.spin_rad_s;
        bodies.push(Body {
            mass_kg: m * k,
            inertia_kg_m2: inertia,
            position_m: centre,
            angle_rad: 0.0,
            velocity_m_s: [
                c.velocity_m_s[0] - w * centre[1],
                c.velocity_m_s[1] + w * centre[0],
            ],
            spin_rad_s: w,
        });
        let local: Vec<[f64; 2]> = own
            .iter()
            .map(|q| [q[0] - centre[0], q[1] - centre[1]])
            .collect();
        let hull = hull_corners(&local);
        points.push(
            local
                .iter()
                .zip(&hull)
                .filter(|(_, h)| **h)
                .map(|(q, _)| *q)
                .collect::<Vec<_>>(),
        );
        outlines.push(Outline {
            nodes: local,
            arc_m: arc[p * c.links..=(p + 1) * c.links].to_vec(),
        });
    }
    let joints: Vec<Joint> = (1..c.pieces)
        .map(|p| Joint {
            prev: *outlines[p - 1].nodes.last().unwrap(),
            next: outlines[p].nodes[0],
        })
        .collect();
    let tolerance = Tolerance {
        position_m: 1e-9 * outer.max(link),
        max_iterations: 50,
        max_turn_rad: 2.0 * c.turn,
    };
    let mut chain = ExactChain::new(bodies, joints, None, tolerance);
    chain.set_floor(
        Floor {
            point_m: floor_point,
            normal,
            friction: c.friction,
        },
        &points,
    );
    chain.set_layers(Layers {
        radius_m: 0.5 * b,
        friction: c.self_friction,
        exclusion_m: std::f64::consts::FRAC_PI_2 * b,
        outlines,
        laid: Outline::default(),
    });
    chain
}
