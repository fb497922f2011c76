//! A value type declared outside the core, the way a node crate declares one: it needs no line
//! in the core, type-checks by name, cooks, caches by content and is refused as a parameter.

use std::hash::Hash;
use std::sync::Arc;

use pyrograph_core::declare::Cook;
use pyrograph_core::fingerprint::{Fingerprinter, hash_f32s};
use pyrograph_core::{
    BuildOptions, CookCtx, DiagnosticKind, Evaluator, Graph, GraphDoc, NodeError, PortType, Registry, TypeInfo, Value, ValueType,
};

/// Heat per cell of a strip.
#[derive(Debug, PartialEq)]
pub struct Heat(Vec<f32>);

impl ValueType for Heat {
    const INFO: &'static TypeInfo = &TypeInfo { name: "Heat", doc: "Heat per cell of a strip.", color: [255, 90, 40] };
    fn hash_into(&self, h: &mut Fingerprinter) {
        self.0.len().hash(h);
        hash_f32s(h, &self.0);
    }
    fn byte_size(&self) -> usize {
        self.0.len() * 4
    }
    fn summary(&self) -> String {
        format!("Heat {} cells", self.0.len())
    }
}

pyrograph_core::node! {
    /// A strip of `cells` cells heated to `level`.
    #[node("test.heat", "Test", Source)]
    pub struct MakeHeat {
        /// Cells in the strip.
        #[range(0, 1000)]
        cells: u32 = 4,
        /// Heat of every cell.
        #[range(0.0, 10.0)]
        level: f32 = 1.0,
    }
    /// The strip.
    -> heat: Arc<Heat>
}

impl Cook for MakeHeat {
    fn cook(self, _: &CookCtx) -> Result<Arc<Heat>, NodeError> {
        Ok(Arc::new(Heat(vec![self.level; self.cells as usize])))
    }
}

pyrograph_core::node! {
    /// The total heat of a strip.
    #[node("test.total", "Test", PerFrame)]
    pub struct Total {
        /// The strip.
        heat: Arc<Heat>,
    }
    /// Its total.
    -> total: f64
}

impl Cook for Total {
    fn cook(self, _: &CookCtx) -> Result<f64, NodeError> {
        Ok(self.heat.0.iter().map(|&x| f64::from(x)).sum())
    }
}

fn registry() -> Registry {
    let mut r = Registry::with_builtins();
    r.declare::<MakeHeat>();
    r.declare::<Total>();
    r
}

fn build(text: &str) -> Result<Graph, pyrograph_core::Diagnostics> {
    let doc = GraphDoc::from_ron(text)?;
    Graph::build(&doc, &registry(), std::path::Path::new("."), &BuildOptions::default())
}

#[test]
fn a_declared_type_flows_between_nodes() {
    let g = build(
        r#"(version: 1, nodes: {"h": (type: "test.heat", params: {"cells": 5, "level": 2.0}), "t": (type: "test.total")},
            edges: [("h.heat", "t.heat")])"#,
    )
    .unwrap_or_else(|d| panic!("{d}"));
    let mut ev = Evaluator::new();
    let heat = ev.output(&g, "h.heat", &CookCtx::new()).unwrap();
    assert_eq!(heat.port_type(), PortType::of::<Heat>());
    assert_eq!((heat.type_name(), heat.summary()), ("Heat".to_string(), "Heat 5 cells".to_string()));
    assert_eq!(heat.downcast::<Heat>().map(|h| h.0.clone()), Some(vec![2.0; 5]));
    assert_eq!(heat.byte_size(), 20);
    let Value::Float(total) = ev.output(&g, "t.total", &CookCtx::new()).unwrap() else { panic!("a float") };
    assert_eq!(total, 10.0);
}

#[test]
fn equal_contents_share_a_fingerprint() {
    let a = Value::custom(Arc::new(Heat(vec![1.0, 2.0])));
    let b = Value::custom(Arc::new(Heat(vec![1.0, 2.0])));
    let c = Value::custom(Arc::new(Heat(vec![1.0, 3.0])));
    assert_eq!(a.fingerprint(), b.fingerprint());
    assert_ne!(a.fingerprint(), c.fingerprint());
    assert!(a.downcast::<Heat>().is_some() && Value::Float(1.0).downcast::<Heat>().is_none());
}

#[test]
fn the_graph_checks_declared_types_by_name() {
    let d =
        build(r#"(version: 1, nodes: {"f": (type: "value.float"), "t": (type: "test.total")}, edges: [("f.value", "t.heat")])"#)
            .err()
            .expect("Float into Heat must fail");
    assert_eq!(d.0[0].kind, DiagnosticKind::TypeMismatch);
    assert!(d.to_string().contains("needs Heat, got Float"), "{d}");
}

#[test]
fn a_declared_type_is_not_a_parameter() {
    let d = build(r#"(version: 1, nodes: {"t": (type: "test.total", params: {"heat": 3.0})})"#).err().expect("not a parameter");
    assert!(d.0.iter().any(|d| d.kind == DiagnosticKind::WrongKind), "{d}");
    assert!(d.to_string().contains("is a Heat input"), "{d}");
}
