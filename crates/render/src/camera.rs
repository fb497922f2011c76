//! A perspective camera (position, target, up, vertical field of view, near/far) and the
//! camera-facing billboard basis.

use glam::{Mat4, Vec3};

/// Which camera or viewport parameter is bad (the render nodes map it to their port).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CameraField {
    /// The eye position.
    Position,
    /// The point looked at.
    Target,
    /// The up hint.
    Up,
    /// The vertical field of view.
    Fov,
    /// The near plane distance.
    Near,
    /// The far plane distance.
    Far,
    /// The image width.
    Width,
    /// The image height.
    Height,
}

/// A bad camera or viewport parameter.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{field:?}: {message}")]
pub struct CameraError {
    /// The offending parameter.
    pub field: CameraField,
    /// What is wrong with it.
    pub message: String,
}

fn err(field: CameraField, message: impl Into<String>) -> CameraError {
    CameraError { field, message: message.into() }
}

/// A right-handed perspective camera looking from `position` at `target`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    position: Vec3,
    target: Vec3,
    up: Vec3,
    fov_y_degrees: f32,
    near: f32,
    far: f32,
}

impl Camera {
    /// A validated camera. The vertical field of view is in degrees, strictly between 0 and 180;
    /// `0 < near < far`; the target must lie beyond the near plane (a camera whose target is
    /// inside its near plane would clip the very thing it looks at) and `up` must not be parallel
    /// to the view direction.
    pub fn new(position: Vec3, target: Vec3, up: Vec3, fov_y_degrees: f32, near: f32, far: f32) -> Result<Self, CameraError> {
        if !position.is_finite() {
            return Err(err(CameraField::Position, format!("must be finite, got {position}")));
        }
        if !target.is_finite() {
            return Err(err(CameraField::Target, format!("must be finite, got {target}")));
        }
        if !up.is_finite() || up.length_squared() < 1e-12 {
            return Err(err(CameraField::Up, format!("must be a finite non-zero vector, got {up}")));
        }
        if !(fov_y_degrees.is_finite() && fov_y_degrees > 0.0 && fov_y_degrees < 180.0) {
            return Err(err(CameraField::Fov, format!("must lie strictly between 0 and 180 degrees, got {fov_y_degrees}")));
        }
        if !(near.is_finite() && near > 0.0) {
            return Err(err(
                CameraField::Near,
                format!("must be positive (the camera cannot sit inside its near plane), got {near}"),
            ));
        }
        if !(far.is_finite() && far > near) {
            return Err(err(CameraField::Far, format!("must be greater than near ({near}), got {far}")));
        }
        let dist = (target - position).length();
        if dist <= near {
            return Err(err(
                CameraField::Target,
                format!("lies inside the near plane (distance {dist} <= near {near}): move the camera back or reduce near"),
            ));
        }
        let dir = (target - position) / dist;
        if up.normalize().cross(dir).length() < 1e-4 {
            return Err(err(CameraField::Up, "is parallel to the view direction; pick another up vector"));
        }
        Ok(Camera { position, target, up: up.normalize(), fov_y_degrees, near, far })
    }

    /// Eye position.
    pub fn position(&self) -> Vec3 {
        self.position
    }

    /// The point looked at.
    pub fn target(&self) -> Vec3 {
        self.target
    }

    /// Normalized up hint.
    pub fn up(&self) -> Vec3 {
        self.up
    }

    /// Near plane distance.
    pub fn near(&self) -> f32 {
        self.near
    }

    /// Far plane distance.
    pub fn far(&self) -> f32 {
        self.far
    }

    /// World → view matrix.
    pub fn view_matrix(&self) -> Mat4 {
        Mat4::look_at_rh(self.position, self.target, self.up)
    }

    /// View → clip matrix for `aspect` = width / height (clip depth 0 at near, 1 at far).
    pub fn projection_matrix(&self, aspect: f32) -> Mat4 {
        Mat4::perspective_rh(self.fov_y_degrees.to_radians(), aspect, self.near, self.far)
    }

    /// Unit vectors `(right, up)` of a billboard at `at` that faces the camera: its normal points
    /// from `at` to the eye, its up is the camera's up hint made perpendicular to that normal.
    pub fn billboard_axes(&self, at: Vec3) -> (Vec3, Vec3) {
        let to_eye = self.position - at;
        let f = if to_eye.length_squared() > 1e-12 { to_eye.normalize() } else { (self.position - self.target).normalize() };
        let mut right = self.up.cross(f);
        if right.length_squared() < 1e-10 {
            // Looking straight along the up hint: fall back to the camera's own right vector.
            right = self.up.cross((self.position - self.target).normalize());
            if right.length_squared() < 1e-10 {
                right = Vec3::X;
            }
        }
        let right = right.normalize();
        (right, f.cross(right))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cam() -> Result<Camera, CameraError> {
        Camera::new(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, Vec3::Y, 60.0, 0.1, 100.0)
    }

    #[test]
    fn bad_parameters_name_their_field() {
        let c = |p: Vec3, t: Vec3, fov: f32, n: f32, f: f32| Camera::new(p, t, Vec3::Y, fov, n, f).map_err(|e| e.field);
        let p = Vec3::new(0.0, 0.0, 5.0);
        assert_eq!(c(p, Vec3::ZERO, 60.0, 0.0, 10.0), Err(CameraField::Near));
        assert_eq!(c(p, Vec3::ZERO, 60.0, -1.0, 10.0), Err(CameraField::Near));
        assert_eq!(c(p, Vec3::ZERO, 60.0, 1.0, 0.5), Err(CameraField::Far));
        assert_eq!(c(p, Vec3::ZERO, 180.0, 0.1, 10.0), Err(CameraField::Fov));
        assert_eq!(c(p, Vec3::new(0.0, 0.0, 4.95), 60.0, 0.1, 10.0), Err(CameraField::Target));
        assert_eq!(c(Vec3::new(f32::NAN, 0.0, 0.0), Vec3::ZERO, 60.0, 0.1, 10.0), Err(CameraField::Position));
        assert_eq!(Camera::new(Vec3::Y * 5.0, Vec3::ZERO, Vec3::Y, 60.0, 0.1, 10.0).map_err(|e| e.field), Err(CameraField::Up));
        assert!(cam().is_ok());
    }

    #[test]
    fn billboard_axes_are_orthonormal_and_face_the_eye() {
        let c = cam().unwrap();
        for at in [Vec3::ZERO, Vec3::new(3.0, 1.0, -2.0), Vec3::new(-4.0, -2.0, 1.0)] {
            let (r, u) = c.billboard_axes(at);
            let normal = r.cross(u);
            let to_eye = (c.position() - at).normalize();
            assert!((normal.dot(to_eye) - 1.0).abs() < 1e-5, "normal {normal} vs to-eye {to_eye}");
            assert!(r.dot(u).abs() < 1e-6 && (r.length() - 1.0).abs() < 1e-6 && (u.length() - 1.0).abs() < 1e-6);
        }
    }
}
