//! Criterion benchmarks of one engine step of the shipped scenes while the coil rolls:
//! ids `step/<scene>/<links_per_turn>`. The scenes are read from `scenes/` and the
//! resolution set by override at run time; building a model is not timed, and a model is
//! rebuilt (untimed) whenever its rolling phase ends.
//!
//! `cargo bench --bench step` (CI only compiles this file).

use std::time::{Duration, Instant};

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};

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

criterion_group!(benches, step);
criterion_main!(benches);
