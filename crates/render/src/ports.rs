//! The camera ports every render node exposes (`width`, `height`, `camera_position`,
//! `camera_target`, `camera_up`, `fov`, `near`, `far`), declared once as [`CameraPorts`] and
//! flattened into the particle, fire and cloth renderers, so their errors name the same ports
//! the same way.

use glam::Vec3;
use pyrograph_core::{NodeError, port};

use crate::camera::CameraField;
use crate::{Camera, CameraError, View};

pyrograph_core::ports! {
    /// A perspective camera and the image size, as ports; each node gives its own defaults
    /// (`camera: CameraPorts = CameraPorts::looking(..)`).
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
        .map_err(camera_error)?;
        View::new(camera, self.width, self.height).map_err(camera_error)
    }
}

impl Default for CameraPorts {
    fn default() -> Self {
        CameraPorts::looking(640, 480, [0.0, 0.0, 10.0], [0.0; 3])
    }
}

/// A camera error as an error on the port it concerns.
fn camera_error(e: CameraError) -> NodeError {
    let port = match e.field {
        CameraField::Width => port!(CameraPorts, width),
        CameraField::Height => port!(CameraPorts, height),
        CameraField::Position => port!(CameraPorts, camera_position),
        CameraField::Target => port!(CameraPorts, camera_target),
        CameraField::Up => port!(CameraPorts, camera_up),
        CameraField::Fov => port!(CameraPorts, fov),
        CameraField::Near => port!(CameraPorts, near),
        CameraField::Far => port!(CameraPorts, far),
    };
    NodeError::port(port, e.message)
}
