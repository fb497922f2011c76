//! Evaluator benchmarks: cold cook, warm (cached) cook and one-parameter re-cook of a 200-node
//! chain and a 200-node fan. `pyrograph bench` prints the same measurements without criterion.

use criterion::{Criterion, criterion_group, criterion_main};
use pyrograph::bench::{Bench, Shape, Workload};

fn evaluator(c: &mut Criterion) {
    let registry = pyrograph_frontend::registry();
    let mut group = c.benchmark_group("evaluator_200");
    for shape in [Shape::Chain, Shape::Fan] {
        for workload in [Workload::Cold, Workload::Warm, Workload::Recook] {
            let mut b = Bench::new(&registry, shape, 200, workload);
            group.bench_function(format!("{shape:?}/{workload:?}").to_lowercase(), |bench| bench.iter(|| b.run()));
        }
    }
    group.finish();
}

criterion_group!(benches, evaluator);
criterion_main!(benches);
