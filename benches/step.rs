//! Criterion benchmarks of one engine step of the shipped scenes while the coil rolls:
//! ids `step/<scene>/<links_per_turn>`. The scenes are read from `scenes/` and the
//! resolution set by override at run time; building a model is not timed, and a model is
//! rebuilt (untimed) whenever its rolling phase ends.
//!
//! And one step of the exact chain (`exact_chain/<case>/<pieces>`, its throughput in pieces):
//! a free chain bent and spinning (`free`, at 100, 1,000 and 10,000 pieces), and the same
//! chain lying on a floor, sliding (`on-floor`, a contact at every node, at the same sizes).
//! The chain is rebuilt (untimed) every 200 steps, so it stays in the state it was built in.
//! And the first step of a tight coil with its thickness (`tight-coil`, 25-200 pieces of
//! 1 mm, 1 mm thick, wound from a radius of half a thickness, spinning at 100 rad/s; the
//! property tests' coil, `tests/exact_chain/coil.rs`), rebuilt before every step.
//!
//! `cargo bench --bench step` (CI only compiles this file).

use std::time::{Duration, Instant};

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};

#[path = "../tests/exact_chain/coil.rs"]
mod coil;
use coil::{Coil, coil_chain};

use uncoil::model::exact_chain::{Body, ExactChain, Floor, Joint, tolerance_for};
use uncoil::model::{Model, Phase};
use uncoil::scene::Scene;
use uncoil::scene::overrides::{Override, scene_file_with_overrides};

fn scene(file: &str, links_per_turn: u32) -> Scene {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(file);
    scene_file_with_overrides(
        &path,
        &[Override::new(
            "discretisation.links_per_turn",
            &links_per_turn.to_string(),
        )],
    )
    .expect("the shipped scene with a valid resolution")
}

fn step(c: &mut Criterion) {
    let mut group = c.benchmark_group("step");
    group.measurement_time(Duration::from_secs(3));
    group.warm_up_time(Duration::from_millis(500));
    group.sample_size(20);
    for (name, file, resolutions) in [
        ("yoga-mat", "yoga-mat.toml", [16, 32, 64]),
        ("thin-tape", "thin-tape.toml", [12, 24, 48]),
    ] {
        for n in resolutions {
            let s = scene(file, n);
            let mut model = Model::new(&s);
            group.bench_function(BenchmarkId::new(name, n), |b| {
                b.iter_custom(|iters| {
                    let mut spent = Duration::ZERO;
                    for _ in 0..iters {
                        if model.phase() != Phase::Rolling {
                            model = Model::new(&s);
                        }
                        let start = Instant::now();
                        std::hint::black_box(model.step());
                        spent += start.elapsed();
                    }
                    spent
                });
            });
        }
    }
    group.finish();
}

/// A chain of `n` links of 1 mm and 1 g along a gentle wave, each spinning a little and the
/// centres moving as the joints allow; on a floor (`on_floor`), laid along it and sliding.
fn exact_chain(n: usize, on_floor: bool) -> ExactChain {
    let (l, m) = (1e-3, 1e-3);
    let mut bodies = Vec::with_capacity(n);
    let (mut node, mut node_v) = ([0.0, 0.0], [0.3, 0.0]);
    for k in 0..n {
        let angle = if on_floor {
            0.0
        } else {
            0.3 * (k as f64 * 0.05).sin()
        };
        let spin = if on_floor {
            0.0
        } else {
            5.0 * (k as f64 * 0.11).cos()
        };
        let half = [0.5 * l * angle.cos(), 0.5 * l * angle.sin()];
        bodies.push(Body {
            mass_kg: m,
            inertia_kg_m2: m * l * l / 12.0,
            position_m: [node[0] + half[0], node[1] + half[1]],
            angle_rad: angle,
            velocity_m_s: [node_v[0] - spin * half[1], node_v[1] + spin * half[0]],
            spin_rad_s: spin,
        });
        node = [node[0] + 2.0 * half[0], node[1] + 2.0 * half[1]];
        node_v = [
            node_v[0] - 2.0 * spin * half[1],
            node_v[1] + 2.0 * spin * half[0],
        ];
    }
    let joints = vec![
        Joint {
            prev: [0.5 * l, 0.0],
            next: [-0.5 * l, 0.0],
        };
        n - 1
    ];
    let mut chain = ExactChain::new(bodies, joints, None, tolerance_for(l));
    if on_floor {
        let points: Vec<Vec<[f64; 2]>> = (0..n)
            .map(|k| {
                if k == 0 {
                    vec![[-0.5 * l, 0.0], [0.5 * l, 0.0]]
                } else {
                    vec![[0.5 * l, 0.0]]
                }
            })
            .collect();
        let floor = Floor {
            point_m: [0.0, 0.0],
            normal: [0.0, 1.0],
            friction: 0.5,
        };
        chain.set_floor(floor, &points);
    }
    chain
}

fn exact_chain_step(c: &mut Criterion) {
    let mut group = c.benchmark_group("exact_chain");
    group.measurement_time(Duration::from_secs(3));
    group.warm_up_time(Duration::from_millis(500));
    group.sample_size(10);
    // On the floor every node is a contact: solved in the banded system with the joints
    // (an active set), linear in the pieces.
    for (case, on_floor, sizes) in [
        ("free", false, &[100, 1_000, 10_000][..]),
        ("on-floor", true, &[100, 1_000, 10_000][..]),
    ] {
        for &n in sizes {
            group.throughput(Throughput::Elements(n as u64));
            let mut chain = exact_chain(n, on_floor);
            let mut taken = 0;
            group.bench_function(BenchmarkId::new(case, n), |b| {
                b.iter_custom(|iters| {
                    let mut spent = Duration::ZERO;
                    for _ in 0..iters {
                        if taken == 200 {
                            chain = exact_chain(n, on_floor);
                            taken = 0;
                        }
                        let start = Instant::now();
                        std::hint::black_box(chain.step(1e-4, [0.0, -9.81]).expect("solves"));
                        spent += start.elapsed();
                        taken += 1;
                    }
                    spent
                });
            });
        }
    }
    // A tight coil with its thickness, every turn on the next: its layers' contacts join
    // pieces far apart along the chain, solved on their Delassus matrix.
    for n in [25, 50, 100, 200] {
        group.throughput(Throughput::Elements(n as u64));
        let coil = Coil {
            pieces: n,
            links: 2,
            thickness_m: 1e-3,
            spin_rad_s: 100.0,
            velocity_m_s: [0.0, 0.0],
            slope: 0.0,
            friction: 0.5,
            self_friction: 0.5,
            turn: 0.15,
        };
        // What the step does, said once: whether it met its tolerance, and how hard it tried.
        let mut chain = coil_chain(&coil);
        let report = chain
            .step(coil.turn / coil.spin_rad_s, [0.0, -9.81])
            .expect("solves");
        eprintln!(
            "tight-coil/{n}: {} contacts, {} iterations, tolerance met: {}, deepest overlap \
             {:.1} % of b",
            chain.contacts().len(),
            report.iterations,
            report.converged,
            100.0 * report.overlap_m / coil.thickness_m
        );
        group.bench_function(BenchmarkId::new("tight-coil", n), |b| {
            b.iter_batched(
                || coil_chain(&coil),
                |mut chain| {
                    let h = coil.turn / coil.spin_rad_s;
                    std::hint::black_box(chain.step(h, [0.0, -9.81]).expect("solves"))
                },
                criterion::BatchSize::PerIteration,
            );
        });
    }
    group.finish();
}

criterion_group!(benches, step, exact_chain_step);
criterion_main!(benches);
