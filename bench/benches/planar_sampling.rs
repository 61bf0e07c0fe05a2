//! Planar sampling throughput: sample N points into a reused buffer after building the
//! cells once (`cargo bench -p strata-bench --bench planar_sampling`).

use std::hint::black_box;
use std::sync::Arc;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use strata_engine::curve::CurveOptions;
use strata_engine::field::{FieldSpec, PlanarDensity};
use strata_engine::fixtures::{along_x, isotropic};
use strata_engine::mesh::shapes;
use strata_engine::planar;
use strata_engine::sample::Sample;

fn fields() -> Vec<(&'static str, FieldSpec)> {
    vec![
        ("isotropic", isotropic()),
        ("anisotropic-4to1", along_x(4.0)),
        (
            "gaussian",
            FieldSpec::Planar {
                density: PlanarDensity::Gaussian {
                    center: [0.5, 0.5],
                    sigma: 0.15,
                    peak: 8.0,
                    base: 0.5,
                },
                direction: [1.0, 0.0, 0.0],
                anisotropy: 1.0,
            },
        ),
    ]
}

fn sample_into(c: &mut Criterion) {
    let mesh = Arc::new(shapes::plane(1.0, 64).expect("plane"));
    let mut group = c.benchmark_group("sample/planar");
    group.sample_size(20);
    for (name, spec) in fields() {
        let field = Arc::new(spec.build(&mesh).expect("field"));
        let (sampler, _) =
            planar::sampler(mesh.clone(), field, &CurveOptions::default()).expect("sampler");
        for n in [10_000usize, 100_000, 1_000_000] {
            let mut buf = vec![Sample::default(); n];
            group.throughput(Throughput::Elements(n as u64));
            group.bench_with_input(BenchmarkId::new(name, n), &n, |b, _| {
                let mut seed = 0u64;
                b.iter(|| {
                    seed += 1;
                    sampler.sample_into(seed, black_box(&mut buf));
                })
            });
        }
    }
    group.finish();
}

fn build_cells(c: &mut Criterion) {
    let mesh = Arc::new(shapes::plane(1.0, 64).expect("plane"));
    let mut group = c.benchmark_group("curve/build_planar");
    group.sample_size(10);
    for (name, spec) in fields() {
        let field = Arc::new(spec.build(&mesh).expect("field"));
        group.bench_function(name, |b| {
            b.iter(|| {
                planar::sampler(mesh.clone(), field.clone(), &CurveOptions::default())
                    .expect("sampler")
            })
        });
    }
    group.finish();
}

criterion_group!(benches, sample_into, build_cells);
criterion_main!(benches);
