//! Reading the camera ports every render node exposes (`camera_position`, `camera_target`,
//! `camera_up`, `fov`, `near`, `far`, `width`, `height`) into a [`View`]; shared by the particle,
//! cloth and (later) spread renderers so their errors name the same ports the same way.

use glam::Vec3;
use pyrograph_core::{Inputs, NodeError};

use crate::{Camera, View};

/// A Vec3 input as a `glam` vector.
pub fn vec3(i: &Inputs<'_>, name: &str) -> Result<Vec3, NodeError> {
    let v = i.vec3(name)?;
    Ok(Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32))
}

/// The camera and viewport described by a node's inputs; errors name the port.
pub fn view_from_inputs(i: &Inputs<'_>) -> Result<View, NodeError> {
    let camera = Camera::new(
        vec3(i, "camera_position")?,
        vec3(i, "camera_target")?,
        vec3(i, "camera_up")?,
        i.float("fov")? as f32,
        i.float("near")? as f32,
        i.float("far")? as f32,
    )
    .map_err(|e| NodeError::port(e.field, e.message))?;
    let w = u32::try_from(i.usize("width")?).map_err(|_| NodeError::port("width", "too large"))?;
    let h = u32::try_from(i.usize("height")?).map_err(|_| NodeError::port("height", "too large"))?;
    View::new(camera, w, h).map_err(|e| NodeError::port(e.field, e.message))
}
