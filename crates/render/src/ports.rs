//! The camera ports every render node exposes (`width`, `height`, `camera_position`,
//! `camera_target`, `camera_up`, `fov`, `near`, `far`), declared once as [`CameraPorts`] and
//! flattened into the particle, fire and cloth renderers, so their errors name the same ports
//! the same way; and [`defaults`], the value of a declared port group at its defaults.

use glam::Vec3;
use pyrograph_core::params::{Field, doc_text};
use pyrograph_core::{Inputs, NodeDesc, NodeError, PortDesc, TimeDep, Value};

use crate::{Camera, View};

/// Declares [`CameraPorts`] and its [`Field`] impl from one field list. Not `ports!`: every
/// renderer frames its own scene, so the defaults are the node's (`camera: CameraPorts =
/// CameraPorts { .. }`), while names, docs and ranges are shared.
macro_rules! camera_ports {
    (
        $(#[doc = $doc:literal])*
        pub struct $name:ident {
            $(
                $(#[doc = $fdoc:literal])*
                $(#[range($lo:expr, $hi:expr)])?
                $field:ident : $fty:ty
            ),* $(,)?
        }
    ) => {
        $(#[doc = $doc])*
        #[derive(Clone, Debug, PartialEq)]
        pub struct $name {
            $( $(#[doc = $fdoc])* pub $field: $fty, )*
        }

        impl Field for $name {
            fn describe(_: &str, _: &str, default: Option<Self>, _: Option<(f64, f64)>, out: &mut Vec<PortDesc>) {
                let d = default.unwrap_or_default();
                $(
                    <$fty as Field>::describe(
                        stringify!($field),
                        &doc_text(&[$($fdoc),*]),
                        Some(d.$field),
                        pyrograph_core::__opt!($((($lo) as f64, ($hi) as f64))?),
                        out,
                    );
                )*
            }

            fn read(inputs: &Inputs<'_>, _: &str) -> Result<Self, NodeError> {
                Ok($name { $( $field: <$fty as Field>::read(inputs, stringify!($field))?, )* })
            }
        }
    };
}

camera_ports! {
    /// A perspective camera and the image size, as ports; the node gives the defaults.
    pub struct CameraPorts {
        /// Image width in pixels.
        #[range(1, 16384)]
        width: u32,
        /// Image height in pixels.
        #[range(1, 16384)]
        height: u32,
        /// Eye position.
        camera_position: [f32; 3],
        /// Point looked at.
        camera_target: [f32; 3],
        /// Up hint.
        camera_up: [f32; 3],
        /// Vertical field of view in degrees.
        #[range(1.0, 179.0)]
        fov: f32,
        /// Near plane distance.
        #[range(0.0001, 1e6)]
        near: f32,
        /// Far plane distance.
        #[range(0.001, 1e7)]
        far: f32,
    }
}

impl CameraPorts {
    /// A 40° camera with a vertical up hint, near 0.1 and far 1000; the usual node defaults.
    pub fn looking(width: u32, height: u32, position: [f32; 3], target: [f32; 3]) -> Self {
        CameraPorts {
            width,
            height,
            camera_position: position,
            camera_target: target,
            camera_up: [0.0, 1.0, 0.0],
            fov: 40.0,
            near: 0.1,
            far: 1000.0,
        }
    }

    /// The camera and viewport; errors name the port.
    pub fn view(&self) -> Result<View, NodeError> {
        let camera = Camera::new(
            Vec3::from_array(self.camera_position),
            Vec3::from_array(self.camera_target),
            Vec3::from_array(self.camera_up),
            self.fov,
            self.near,
            self.far,
        )
        .map_err(|e| NodeError::port(e.field, e.message))?;
        View::new(camera, self.width, self.height).map_err(|e| NodeError::port(e.field, e.message))
    }
}

impl Default for CameraPorts {
    fn default() -> Self {
        CameraPorts::looking(640, 480, [0.0, 0.0, 10.0], [0.0; 3])
    }
}

/// A declared port group (a `ports!` struct) at its declared defaults, so an algorithm's
/// parameter struct that *is* the group has a `Default` without restating the values.
///
/// # Panics
/// When a port of the group has no default: a declaration error, caught by any test that
/// builds the default.
pub fn defaults<T: Field>() -> T {
    let mut desc = NodeDesc::new("defaults", "", TimeDep::PerFrame, "");
    T::describe("", "", None, None, &mut desc.inputs);
    let values: Vec<Value> = desc.inputs.iter().filter_map(|p| p.default.clone()).collect();
    assert_eq!(values.len(), desc.inputs.len(), "every port of a group read by `defaults` has a default");
    T::read(&Inputs::new(&desc, &values), "").unwrap_or_else(|e| panic!("a declared default does not read back: {e}"))
}
