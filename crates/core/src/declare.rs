//! Typed node declarations: one [`node!`](crate::node) declaration gives a node's port
//! descriptions (name, type, default, range, doc) *and* a typed reader, so a cook reads
//! `p.turbulence: f32`, never a port by a string. Shared port groups ([`ports!`](crate::ports))
//! are declared once and flattened into every node that uses them; enumerations
//! ([`choice!`](crate::choice)) carry their option names.
//!
//! Written with `macro_rules!` rather than a proc-macro crate: the declarations are plain
//! field lists, and a proc-macro would add `syn`/`quote` to every build for no expressive gain.

use std::marker::PhantomData;
use std::ops::Deref;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use crate::ctx::CookCtx;
use crate::error::NodeError;
use crate::node::{Inputs, Node, NodeDesc, PathRole, PortDesc};
use crate::value::{Clip, Contours, Image, Mask, Points, PortType, Value};

mod anim_port;
pub use anim_port::{Anim, AnimError};

/// A type that one port carries: how it is described and how it converts to and from a [`Value`].
pub trait Port: Sized {
    /// The port's type.
    fn port_type() -> PortType;
    /// The value, for a default or an output.
    fn into_value(self) -> Value;
    /// Converts a port's value; the error text is wrapped with the port's name by the caller.
    fn from_value(v: &Value) -> Result<Self, String>;
    /// Option names, for enumerations.
    fn options() -> Vec<String> {
        Vec::new()
    }
    /// How a path resolves, for paths.
    fn path_role() -> Option<PathRole> {
        None
    }
    /// Whether the node samples the port itself over time ([`Anim`]).
    fn sampled_by_node() -> bool {
        false
    }
    /// Converts port `port`'s value, knowing the port (its name and range); [`Anim`] keeps them to
    /// check and name every value it samples.
    fn from_port(v: &Value, _port: &PortDesc) -> Result<Self, String> {
        Self::from_value(v)
    }
}

/// Something a declared field contributes: one port (every [`Port`]) or a group of them
/// ([`ports!`](crate::ports) structs, or a hand-written impl for ports numbered at run time).
pub trait Field: Sized {
    /// Appends this field's port descriptions. `name` and `doc` are the field's; `default` and
    /// `range` its `= value` and `#[range(lo, hi)]`.
    fn describe(name: &str, doc: &str, default: Option<Self>, range: Option<(f64, f64)>, out: &mut Vec<PortDesc>);
    /// Reads the field from a cook's inputs.
    fn read(inputs: &Inputs<'_>, name: &str) -> Result<Self, NodeError>;
}

impl<T: Port> Field for T {
    fn describe(name: &str, doc: &str, default: Option<Self>, range: Option<(f64, f64)>, out: &mut Vec<PortDesc>) {
        out.push(PortDesc {
            default: default.map(Port::into_value),
            range,
            options: T::options(),
            path_role: T::path_role(),
            sampled_by_node: T::sampled_by_node(),
            ..PortDesc::new(port_name(name), T::port_type(), doc)
        });
    }

    fn read(inputs: &Inputs<'_>, name: &str) -> Result<Self, NodeError> {
        let name = port_name(name);
        let (value, port) = inputs.get_port(name)?;
        // The loader checks ranges of values written in the file; a value that arrives over an
        // edge (or a frame of a lifted clip) is checked here, so no node clamps it silently.
        check_range(port, value).map_err(|e| NodeError::port(name, e))?;
        T::from_port(value, port).map_err(|e| NodeError::port(name, e))
    }
}

/// Whether a number fits its port's range (anything else passes): what every declared field
/// checks on read, and what a node whose ports are known only at run time (a Python plugin)
/// checks itself.
pub fn check_range(port: &PortDesc, value: &Value) -> Result<(), String> {
    let Some((lo, hi)) = port.range else { return Ok(()) };
    let x = match value {
        Value::Float(x) => *x,
        Value::Int(i) => *i as f64,
        _ => return Ok(()),
    };
    if (lo..=hi).contains(&x) { Ok(()) } else { Err(format!("{x} is outside the range {lo}..={hi}")) }
}

/// The port name of a field: `r#type` is the port `type`.
pub fn port_name(field: &str) -> &str {
    field.strip_prefix("r#").unwrap_or(field)
}

/// A node's declared inputs and outputs; implemented by [`node!`](crate::node).
pub trait Declared: Sized + Send + Sync + 'static {
    /// What `cook` returns: the one output's value, or the outputs struct in port order.
    type Outputs: OutputSet;
    /// The static description.
    fn desc() -> NodeDesc;
    /// Reads every input of a cook.
    fn read(inputs: &Inputs<'_>) -> Result<Self, NodeError>;
}

/// A node's outputs as port values, in declaration order; implemented by [`node!`](crate::node)
/// for an outputs struct, and here for any single port value (a node with one output returns it).
pub trait OutputSet {
    /// The values, in port order.
    fn into_values(self) -> Vec<Value>;
}

impl<T: Port> OutputSet for T {
    fn into_values(self) -> Vec<Value> {
        vec![self.into_value()]
    }
}

/// What a declared node computes: the one function a node author writes beside its declaration.
pub trait Cook: Declared {
    /// Computes the outputs from the typed inputs.
    fn cook(self, ctx: &CookCtx) -> Result<Self::Outputs, NodeError>;

    /// The node, ready for [`crate::Registry::add`].
    fn node() -> Arc<dyn Node> {
        Arc::new(Typed::<Self> { desc: Self::desc(), marker: PhantomData })
    }
}

struct Typed<T> {
    desc: NodeDesc,
    marker: PhantomData<fn() -> T>,
}

impl<T: Cook> Node for Typed<T> {
    fn desc(&self) -> &NodeDesc {
        &self.desc
    }
    fn cook(&self, inputs: &Inputs<'_>, ctx: &CookCtx) -> Result<Vec<Value>, NodeError> {
        Ok(T::read(inputs)?.cook(ctx)?.into_values())
    }
}

/// Joins doc-comment lines (`/// text` arrives as `" text"`): lines of a paragraph with spaces,
/// paragraphs with a blank line, so the first line is the summary.
pub fn doc_text(lines: &[&str]) -> String {
    let mut out = String::new();
    let mut blank = false;
    for line in lines {
        let line = line.strip_prefix(' ').unwrap_or(line).trim_end();
        if line.is_empty() {
            blank = !out.is_empty();
            continue;
        }
        if blank {
            out.push_str("\n\n");
            blank = false;
        } else if !out.is_empty() {
            out.push(' ');
        }
        out.push_str(line);
    }
    out
}

/// The f64 an f32 was written as: `0.1f32` is `0.1`, not `0.10000000149011612`, so defaults
/// print as declared; converting back to f32 gives the same f32.
fn f32_to_f64_shortest(x: f32) -> f64 {
    x.to_string().parse().unwrap_or(f64::from(x))
}

fn wrong(wanted: &str, got: &Value) -> String {
    format!("needs {wanted}, got {}", got.type_name())
}

// ---------------------------------------------------------------------------------------------
// Scalars
// ---------------------------------------------------------------------------------------------

impl Port for f64 {
    fn port_type() -> PortType {
        PortType::Float
    }
    fn into_value(self) -> Value {
        Value::Float(self)
    }
    fn from_value(v: &Value) -> Result<Self, String> {
        match v {
            Value::Float(x) => Ok(*x),
            // An Int on a Float port is widened, as graph files write `2` for `2.0`.
            Value::Int(x) => Ok(*x as f64),
            other => Err(wrong("Float", other)),
        }
    }
}

impl Port for f32 {
    fn port_type() -> PortType {
        PortType::Float
    }
    fn into_value(self) -> Value {
        Value::Float(f32_to_f64_shortest(self))
    }
    fn from_value(v: &Value) -> Result<Self, String> {
        // Ports store f64; the nodes that declare f32 compute in f32, so rounding here is the intent.
        f64::from_value(v).map(|x| x as f32)
    }
}

/// Ports whose type is one `Value` variant, read back only from that variant: the type, the
/// variant (also the type's name in errors) and a doc line each.
macro_rules! value_port {
    ($($(#[$doc:meta])* $t:ty => $variant:ident),* $(,)?) => {$(
        $(#[$doc])*
        impl Port for $t {
            fn port_type() -> PortType {
                PortType::$variant
            }
            fn into_value(self) -> Value {
                Value::$variant(self)
            }
            fn from_value(v: &Value) -> Result<Self, String> {
                match v {
                    Value::$variant(x) => Ok(x.to_owned()),
                    other => Err(wrong(stringify!($variant), other)),
                }
            }
        }
    )*};
}
value_port! {
    /// An Int port.
    i64 => Int,
    /// A Bool port.
    bool => Bool,
    /// A Color port: linear RGBA.
    [f32; 4] => Color,
    /// A Vec2 port.
    [f64; 2] => Vec2,
    /// A Vec3 port.
    [f64; 3] => Vec3,
    /// A String port.
    String => String,
}

macro_rules! int_port {
    ($($t:ty),*) => {$(
        impl Port for $t {
            fn port_type() -> PortType {
                PortType::Int
            }
            fn into_value(self) -> Value {
                Value::Int(i64::try_from(self).unwrap_or(i64::MAX))
            }
            fn from_value(v: &Value) -> Result<Self, String> {
                let x = i64::from_value(v)?;
                <$t>::try_from(x).map_err(|_| {
                    format!("{x} is outside {}..={}", <$t>::MIN, <$t>::MAX)
                })
            }
        }
    )*};
}
int_port!(i32, u8, u16, u32, u64, usize);

impl Port for [f32; 3] {
    fn port_type() -> PortType {
        PortType::Vec3
    }
    fn into_value(self) -> Value {
        Value::Vec3(self.map(f32_to_f64_shortest))
    }
    fn from_value(v: &Value) -> Result<Self, String> {
        // As for f32: the nodes that declare [f32; 3] compute in f32.
        <[f64; 3]>::from_value(v).map(|x| x.map(|c| c as f32))
    }
}

macro_rules! path_port {
    ($(#[$doc:meta])* $name:ident, $role:ident) => {
        $(#[$doc])*
        #[derive(Clone, Debug, PartialEq, Eq)]
        pub struct $name(pub PathBuf);

        impl Deref for $name {
            type Target = Path;
            fn deref(&self) -> &Path {
                &self.0
            }
        }

        impl From<&str> for $name {
            fn from(s: &str) -> Self {
                $name(PathBuf::from(s))
            }
        }

        impl Port for $name {
            fn port_type() -> PortType {
                PortType::Path
            }
            fn into_value(self) -> Value {
                Value::Path(self.0)
            }
            fn from_value(v: &Value) -> Result<Self, String> {
                match v {
                    Value::Path(x) => Ok($name(x.clone())),
                    other => Err(wrong("Path", other)),
                }
            }
            fn path_role() -> Option<PathRole> {
                Some(PathRole::$role)
            }
        }
    };
}
path_port!(
    /// A path read by the node; resolved against the graph file's folder by the loader.
    InputPath,
    Input
);
path_port!(
    /// A path the node writes; resolved against the render's output folder by the loader.
    OutputPath,
    Output
);

macro_rules! shared_port {
    ($($t:ident),* $(,)?) => {$(
        impl Port for Arc<$t> {
            fn port_type() -> PortType {
                PortType::$t
            }
            fn into_value(self) -> Value {
                Value::$t(self)
            }
            fn from_value(v: &Value) -> Result<Self, String> {
                match v {
                    Value::$t(x) => Ok(Arc::clone(x)),
                    other => Err(wrong(stringify!($t), other)),
                }
            }
        }
    )*};
}
shared_port!(Image, Mask, Contours, Points);

/// Every type a node crate declares with [`crate::value::ValueType`] is a port type as `Arc<T>`.
impl<T: crate::value::ValueType> Port for Arc<T> {
    fn port_type() -> PortType {
        PortType::of::<T>()
    }
    fn into_value(self) -> Value {
        Value::custom(self)
    }
    fn from_value(v: &Value) -> Result<Self, String> {
        v.downcast::<T>().ok_or_else(|| wrong(T::INFO.name, v))
    }
}

/// A clip whose frames are `T`s: the port type `Clip<T>`.
pub struct ClipOf<T> {
    clip: Clip,
    marker: PhantomData<fn() -> T>,
}

impl<T> ClipOf<T> {
    /// Wraps a clip (its element type is checked by the graph, not here).
    pub fn new(clip: Clip) -> Self {
        ClipOf { clip, marker: PhantomData }
    }

    /// The clip.
    pub fn into_inner(self) -> Clip {
        self.clip
    }
}

impl<T> Clone for ClipOf<T> {
    fn clone(&self) -> Self {
        ClipOf::new(self.clip.clone())
    }
}

impl<T> std::fmt::Debug for ClipOf<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        self.clip.fmt(f)
    }
}

impl<T> Deref for ClipOf<T> {
    type Target = Clip;
    fn deref(&self) -> &Clip {
        &self.clip
    }
}

impl<T: Port> Port for ClipOf<T> {
    fn port_type() -> PortType {
        PortType::clip_of(T::port_type())
    }
    fn into_value(self) -> Value {
        Value::Clip(self.clip)
    }
    fn from_value(v: &Value) -> Result<Self, String> {
        match v {
            Value::Clip(x) => Ok(ClipOf::new(x.clone())),
            other => Err(wrong("Clip", other)),
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Declaration macros
// ---------------------------------------------------------------------------------------------

/// `Some(x)` for a present token, `None` for none: the `= default` and `#[range]` of a field.
#[doc(hidden)]
#[macro_export]
macro_rules! __opt {
    () => {
        None
    };
    ($e:expr) => {
        Some($e)
    };
}

/// The port name of a declared field, checked at compile time: `port!(Crop, width)` is
/// `"width"`, and fails to build if `Crop` has no field `width`. For errors that name a port
/// (`NodeError::port(port!(Crop, width), ..)`) without restating its name as a string.
#[macro_export]
macro_rules! port {
    ($owner:ty, $field:ident) => {{
        let _ = |p: &$owner| {
            let _ = &p.$field;
        };
        $crate::declare::port_name(stringify!($field))
    }};
}

/// Declares a node: a struct of its inputs (each field one port, or a [`ports!`](crate::ports)
/// group flattened in), its outputs, and from them its [`NodeDesc`] and typed reader. The author
/// then writes `impl Cook for Name { fn cook(self, ctx) -> Result<.., NodeError> }` and registers
/// `Name::node()`.
///
/// A field without `= default` is a required input; `#[range(lo, hi)]` bounds a number.
///
/// A node with one output declares it as `-> name: Type`, and its cook returns that value; a node
/// with several declares a struct of them (`pub struct NameOut { a: A, b: B }`), which its cook
/// returns. The first example has one output, the second two.
///
/// ```
/// use std::sync::Arc;
/// use pyrograph_core::declare::Cook;
/// use pyrograph_core::{CookCtx, Image, NodeError};
///
/// pyrograph_core::node! {
///     /// Multiplies every sample by a gain.
///     #[node("example.gain", "Examples", PerFrame)]
///     pub struct Gain {
///         /// The image.
///         image: Arc<Image>,
///         /// The factor.
///         #[range(0.0, 8.0)]
///         gain: f32 = 1.0,
///     }
///     /// The brighter image.
///     -> image: Arc<Image>
/// }
///
/// impl Cook for Gain {
///     fn cook(self, _: &CookCtx) -> Result<Arc<Image>, NodeError> {
///         let mut img = (*self.image).clone();
///         img.data_mut().iter_mut().for_each(|v| *v *= self.gain);
///         Ok(Arc::new(img))
///     }
/// }
///
/// let desc = Gain::node().desc().clone();
/// assert_eq!(desc.inputs[1].name, "gain");
/// assert_eq!(desc.inputs[1].range, Some((0.0, 8.0)));
/// assert_eq!(desc.outputs[0].name, "image");
/// ```
///
/// ```
/// use pyrograph_core::declare::Cook;
/// use pyrograph_core::{CookCtx, NodeError};
///
/// pyrograph_core::node! {
///     /// Splits a number into its whole and fractional parts.
///     #[node("example.split", "Examples", PerFrame)]
///     pub struct Split {
///         /// The number.
///         x: f64 = 0.0,
///     }
///     pub struct SplitOut {
///         /// The whole part.
///         whole: f64,
///         /// The fractional part.
///         fraction: f64,
///     }
/// }
///
/// impl Cook for Split {
///     fn cook(self, _: &CookCtx) -> Result<SplitOut, NodeError> {
///         Ok(SplitOut { whole: self.x.trunc(), fraction: self.x.fract() })
///     }
/// }
///
/// assert_eq!(Split::node().desc().outputs[1].name, "fraction");
/// ```
#[macro_export]
macro_rules! node {
    // The input struct and the `Declared` impl, for both forms below.
    (
        @declare [
            $(#[doc = $doc:literal])*
            #[node($type_name:literal, $category:literal, $time:ident)]
            $vis:vis struct $name:ident {
                $(
                    $(#[doc = $fdoc:literal])*
                    $(#[range($lo:expr, $hi:expr)])?
                    $field:ident : $fty:ty $(= $fdef:expr)?
                ),* $(,)?
            }
        ]
        type Outputs = $outs:ty;
        $(
            $(#[doc = $odoc:literal])*
            $ofield:ident : $oty:ty
        ),*
    ) => {
        $(#[doc = $doc])*
        #[derive(Clone, Debug)]
        $vis struct $name {
            $( $(#[doc = $fdoc])* pub $field: $fty, )*
        }

        impl $crate::declare::Declared for $name {
            type Outputs = $outs;

            fn desc() -> $crate::NodeDesc {
                let mut desc = $crate::NodeDesc::new(
                    $type_name,
                    $category,
                    $crate::TimeDep::$time,
                    &$crate::declare::doc_text(&[$($doc),*]),
                );
                $(
                    <$fty as $crate::declare::Field>::describe(
                        stringify!($field),
                        &$crate::declare::doc_text(&[$($fdoc),*]),
                        $crate::__opt!($($fdef)?),
                        $crate::__opt!($((($lo) as f64, ($hi) as f64))?),
                        &mut desc.inputs,
                    );
                )*
                $(
                    desc.outputs.push($crate::PortDesc::new(
                        $crate::declare::port_name(stringify!($ofield)),
                        <$oty as $crate::declare::Port>::port_type(),
                        &$crate::declare::doc_text(&[$($odoc),*]),
                    ));
                )*
                desc
            }

            fn read(inputs: &$crate::Inputs<'_>) -> Result<Self, $crate::NodeError> {
                Ok($name {
                    $( $field: <$fty as $crate::declare::Field>::read(inputs, stringify!($field))?, )*
                })
            }
        }
    };
    // One output, `-> name: Type`: the cook returns the value itself. The inputs are passed on as
    // they are, for `@declare` to read.
    (
        $(#[$($attr:tt)*])*
        $vis:vis struct $name:ident $inputs:tt
        $(#[doc = $odoc:literal])*
        -> $ofield:ident : $oty:ty
    ) => {
        $crate::node! {
            @declare [$(#[$($attr)*])* $vis struct $name $inputs]
            type Outputs = $oty;
            $(#[doc = $odoc])* $ofield : $oty
        }
    };
    // Several outputs, as a struct the cook returns.
    (
        $(#[$($attr:tt)*])*
        $vis:vis struct $name:ident $inputs:tt
        $ovis:vis struct $out:ident {
            $(
                $(#[doc = $odoc:literal])*
                $ofield:ident : $oty:ty
            ),* $(,)?
        }
    ) => {
        $crate::node! {
            @declare [$(#[$($attr)*])* $vis struct $name $inputs]
            type Outputs = $out;
            $( $(#[doc = $odoc])* $ofield : $oty ),*
        }

        #[doc = concat!("The outputs of [`", stringify!($name), "`], in port order.")]
        $ovis struct $out {
            $( $(#[doc = $odoc])* pub $ofield: $oty, )*
        }

        impl $crate::declare::OutputSet for $out {
            fn into_values(self) -> Vec<$crate::Value> {
                vec![$( $crate::declare::Port::into_value(self.$ofield) ),*]
            }
        }
    };
}

/// Declares a group of ports shared by several nodes (a camera, a colour ramp): a struct whose
/// fields are ports, flattened into any [`node!`](crate::node) that has a field of its type.
/// Field syntax is that of `node!`. A node's field `camera: CameraPorts = CameraPorts { .. }`
/// overrides every default of the group for that node (names, docs and ranges stay shared).
#[macro_export]
macro_rules! ports {
    // The struct and its `Field` impl, for both forms below.
    (
        @group
        $(#[$meta:meta])*
        $vis:vis struct $name:ident {
            $(
                $(#[doc = $fdoc:literal])*
                $(#[range($lo:expr, $hi:expr)])?
                $field:ident : $fty:ty $(= $fdef:expr)?
            ),* $(,)?
        }
    ) => {
        $(#[$meta])*
        #[derive(Clone, Debug)]
        $vis struct $name {
            $( $(#[doc = $fdoc])* pub $field: $fty, )*
        }

        impl $crate::declare::Field for $name {
            fn describe(
                _: &str,
                _: &str,
                default: Option<Self>,
                _: Option<(f64, f64)>,
                out: &mut Vec<$crate::PortDesc>,
            ) {
                // A node's `group: Group = value` gives every port of the group its default from
                // `value` (each renderer frames its own scene); else the group's declared defaults.
                $(
                    let declared: Option<$fty> = $crate::__opt!($($fdef)?);
                    <$fty as $crate::declare::Field>::describe(
                        stringify!($field),
                        &$crate::declare::doc_text(&[$($fdoc),*]),
                        match &default {
                            Some(d) => Some(d.$field.clone()),
                            None => declared,
                        },
                        $crate::__opt!($((($lo) as f64, ($hi) as f64))?),
                        out,
                    );
                )*
            }

            fn read(inputs: &$crate::Inputs<'_>, _: &str) -> Result<Self, $crate::NodeError> {
                Ok($name {
                    $( $field: <$fty as $crate::declare::Field>::read(inputs, stringify!($field))?, )*
                })
            }
        }
    };
    // A group whose every port has a default (parameters, not inputs) also gets a `Default` made
    // of those values, so an algorithm's settings struct that *is* the group has one without
    // restating them.
    (
        $(#[$meta:meta])*
        $vis:vis struct $name:ident {
            $(
                $(#[doc = $fdoc:literal])*
                $(#[range($lo:expr, $hi:expr)])?
                $field:ident : $fty:ty = $fdef:expr
            ),* $(,)?
        }
    ) => {
        $crate::ports! {
            @group
            $(#[$meta])*
            $vis struct $name {
                $( $(#[doc = $fdoc])* $(#[range($lo, $hi)])? $field : $fty = $fdef, )*
            }
        }

        impl Default for $name {
            fn default() -> Self {
                $name { $( $field: $fdef, )* }
            }
        }
    };
    // A group with required inputs.
    (
        $(#[$meta:meta])*
        $vis:vis struct $name:ident {
            $(
                $(#[doc = $fdoc:literal])*
                $(#[range($lo:expr, $hi:expr)])?
                $field:ident : $fty:ty $(= $fdef:expr)?
            ),* $(,)?
        }
    ) => {
        $crate::ports! {
            @group
            $(#[$meta])*
            $vis struct $name {
                $( $(#[doc = $fdoc])* $(#[range($lo, $hi)])? $field : $fty $(= $fdef)?, )*
            }
        }
    };
}

/// Declares an enumeration carried by an Enum port: each variant with its option name.
/// Gives `NAMES`, `name()`, `parse()` and the [`Port`] impl.
#[macro_export]
macro_rules! choice {
    (
        $(#[$meta:meta])*
        $vis:vis enum $name:ident {
            $( $(#[doc = $vdoc:literal])* $variant:ident = $text:literal ),+ $(,)?
        }
    ) => {
        $(#[$meta])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
        $vis enum $name {
            $( $(#[doc = $vdoc])* $variant, )+
        }

        impl $name {
            /// Every option's name, in order.
            pub const NAMES: &'static [&'static str] = &[$($text),+];

            /// The option's name.
            pub fn name(self) -> &'static str {
                match self {
                    $( $name::$variant => $text, )+
                }
            }

            /// The option named `text`.
            pub fn parse(text: &str) -> Option<Self> {
                match text {
                    $( $text => Some($name::$variant), )+
                    _ => None,
                }
            }
        }

        impl $crate::declare::Port for $name {
            fn port_type() -> $crate::PortType {
                $crate::PortType::Enum
            }
            fn into_value(self) -> $crate::Value {
                $crate::Value::Enum(self.name().to_string())
            }
            fn from_value(v: &$crate::Value) -> Result<Self, String> {
                match v {
                    $crate::Value::Enum(text) => $name::parse(text).ok_or_else(|| {
                        format!("unknown option '{text}' ({})", Self::NAMES.join(", "))
                    }),
                    other => Err(format!("needs Enum, got {}", other.type_name())),
                }
            }
            fn options() -> Vec<String> {
                Self::NAMES.iter().map(|s| s.to_string()).collect()
            }
        }
    };
}

#[cfg(test)]
mod tests;
