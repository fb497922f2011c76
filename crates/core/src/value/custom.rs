//! Value types declared outside the core. A node crate that owns a type (a mesh, a learned
//! model, a wind field) implements [`ValueType`] for it; its ports are then `Arc<T>` fields of a
//! `node!` declaration, the graph type-checks it by [`TypeInfo`], and the evaluator hashes,
//! sizes and describes it through the trait. The core does not name any such type.

use std::any::Any;
use std::fmt;
use std::sync::Arc;

use crate::fingerprint::Fingerprinter;

/// What the graph, the editor and `pyrograph nodes` know of a declared type.
#[derive(Debug, PartialEq, Eq, Hash)]
pub struct TypeInfo {
    /// The type's name on ports and in messages (`Mesh`), unique among all types.
    pub name: &'static str,
    /// One line on what a value is, citing its paper section.
    pub doc: &'static str,
    /// The editor's pin and wire colour, sRGB.
    pub color: [u8; 3],
}

/// A value type owned by a node crate.
///
/// ```
/// use pyrograph_core::fingerprint::Fingerprinter;
/// use pyrograph_core::value::{TypeInfo, ValueType};
///
/// #[derive(Debug)]
/// struct Heat(Vec<f32>);
///
/// impl ValueType for Heat {
///     const INFO: &'static TypeInfo = &TypeInfo { name: "Heat", doc: "Heat per cell.", color: [255, 90, 40] };
///     fn hash_into(&self, h: &mut Fingerprinter) {
///         pyrograph_core::fingerprint::hash_f32s(h, &self.0);
///     }
///     fn byte_size(&self) -> usize {
///         self.0.len() * 4
///     }
///     fn summary(&self) -> String {
///         format!("Heat {} cells", self.0.len())
///     }
/// }
/// assert_eq!(pyrograph_core::PortType::of::<Heat>().to_string(), "Heat");
/// ```
pub trait ValueType: Any + Send + Sync + fmt::Debug {
    /// The type's description (a `&'static` so port types stay cheap to copy and compare).
    const INFO: &'static TypeInfo;
    /// Feeds the value's content into a hasher: equal values must hash equal, so unchanged
    /// outputs stop re-cooking downstream.
    fn hash_into(&self, h: &mut Fingerprinter);
    /// Approximate memory held, for cache budgets.
    fn byte_size(&self) -> usize;
    /// A one-line description for the editor and `render` reports.
    fn summary(&self) -> String;
}

/// The object-safe face of [`ValueType`] that [`crate::Value::Custom`] holds; implemented for
/// every `ValueType`, never by hand.
pub trait CustomValue: Any + Send + Sync + fmt::Debug {
    /// The type's description.
    fn type_info(&self) -> &'static TypeInfo;
    /// See [`ValueType::hash_into`].
    fn hash_value(&self, h: &mut Fingerprinter);
    /// See [`ValueType::byte_size`].
    fn value_bytes(&self) -> usize;
    /// See [`ValueType::summary`].
    fn value_summary(&self) -> String;
}

impl<T: ValueType> CustomValue for T {
    fn type_info(&self) -> &'static TypeInfo {
        T::INFO
    }
    fn hash_value(&self, h: &mut Fingerprinter) {
        self.hash_into(h);
    }
    fn value_bytes(&self) -> usize {
        self.byte_size()
    }
    fn value_summary(&self) -> String {
        self.summary()
    }
}

/// Whether the value is held outside `a` too (the frame cache keeps in-use frames).
pub(crate) fn shared(a: &Arc<dyn CustomValue>) -> bool {
    Arc::strong_count(a) > 1
}
