//! Evaluator benchmark graphs and timings shared by `pyrograph bench` and the criterion benches:
//! cold cook, warm (all cached) cook and one-parameter re-cook of a 200-node chain and fan.

use std::time::{Duration, Instant};

use pyrograph_core::{BuildOptions, CookCtx, Evaluator, Graph, GraphDoc, NodeDoc, ParamValue, Registry};

/// The shape of a benchmark graph.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shape {
    /// `value.float` → 199 `math.add` in a line; the target is the last.
    Chain,
    /// `value.float` → 199 `math.add` side by side; the targets are all of them.
    Fan,
}

/// A benchmark document of `n` nodes; `tweak` sets the parameter that the re-cook changes.
pub fn document(shape: Shape, n: usize, tweak: f64) -> GraphDoc {
    let mut doc = GraphDoc::new();
    doc.add_node("src", NodeDoc::new("value.float").param("value", ParamValue::Float(1.0)));
    for i in 1..n {
        let b = if i == n / 2 { tweak } else { 1.0 };
        doc.add_node(&format!("n{i}"), NodeDoc::new("math.add").param("b", ParamValue::Float(b)));
        let from = match (shape, i) {
            (Shape::Chain, 1) | (Shape::Fan, _) => "src.value".to_string(),
            (Shape::Chain, _) => format!("n{}.value", i - 1),
        };
        doc.connect(&from, &format!("n{i}.a"));
    }
    doc
}

/// Targets to cook for a shape.
pub fn targets(shape: Shape, n: usize) -> Vec<String> {
    match shape {
        Shape::Chain => vec![format!("n{}", n - 1)],
        Shape::Fan => (1..n).map(|i| format!("n{i}")).collect(),
    }
}

/// Builds a benchmark graph.
pub fn graph(registry: &Registry, shape: Shape, n: usize, tweak: f64) -> Graph {
    let doc = document(shape, n, tweak);
    // The benchmark documents are generated above and always valid.
    Graph::build(&doc, registry, std::path::Path::new("."), &BuildOptions::default())
        .unwrap_or_else(|d| panic!("benchmark graph invalid: {d}"))
}

/// Which evaluator workload to time.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Workload {
    /// A fresh evaluator each time.
    Cold,
    /// Everything already cached.
    Warm,
    /// The middle node's parameter alternates, so it and its downstream re-cook.
    Recook,
}

/// Prepared state for timing one workload.
pub struct Bench {
    graphs: [Graph; 2],
    targets: Vec<String>,
    eval: Evaluator,
    flip: usize,
    workload: Workload,
}

impl Bench {
    /// Prepares graphs (and, for warm/re-cook, a primed cache).
    pub fn new(registry: &Registry, shape: Shape, n: usize, workload: Workload) -> Self {
        let graphs = [graph(registry, shape, n, 1.0), graph(registry, shape, n, 2.0)];
        let mut b = Bench { graphs, targets: targets(shape, n), eval: Evaluator::new(), flip: 0, workload };
        b.run();
        b
    }

    /// One timed iteration; returns how many nodes cooked.
    pub fn run(&mut self) -> usize {
        if self.workload == Workload::Cold {
            self.eval = Evaluator::new();
        }
        if self.workload == Workload::Recook {
            self.flip ^= 1;
        }
        let targets: Vec<&str> = self.targets.iter().map(String::as_str).collect();
        let _ = self.eval.cook(&self.graphs[self.flip], &targets, &CookCtx::new());
        self.eval.take_log().len()
    }
}

/// Median and minimum of `iters` runs of a workload.
pub fn time(registry: &Registry, shape: Shape, n: usize, workload: Workload, iters: usize) -> (Duration, Duration, usize) {
    let mut b = Bench::new(registry, shape, n, workload);
    let mut samples: Vec<Duration> = Vec::with_capacity(iters);
    let mut cooked = 0;
    for _ in 0..iters.max(1) {
        let t = Instant::now();
        cooked = b.run();
        samples.push(t.elapsed());
    }
    samples.sort();
    (samples[samples.len() / 2], samples[0], cooked)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recook_touches_the_middle_node_and_its_downstream_only() {
        let r = pyrograph_frontend::registry();
        let mut chain = Bench::new(&r, Shape::Chain, 200, Workload::Recook);
        assert_eq!(chain.run(), 100, "n100..n199");
        let mut fan = Bench::new(&r, Shape::Fan, 200, Workload::Recook);
        assert_eq!(fan.run(), 1);
        let mut warm = Bench::new(&r, Shape::Fan, 200, Workload::Warm);
        assert_eq!(warm.run(), 0);
        let mut cold = Bench::new(&r, Shape::Chain, 200, Workload::Cold);
        assert_eq!(cold.run(), 200);
    }
}
