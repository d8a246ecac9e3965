//! An orbit camera: it turns around a target point, zooms towards it and pans in the view
//! plane. The scene is drawn relative to the mesh's centre, so `f32` keeps its precision
//! whatever the mesh's coordinates are.
use glam::{Mat4, Vec3};

/// Vertical field of view, in radians.
const FOV_Y: f32 = 0.8;

/// Orbit camera state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OrbitCamera {
    /// The point looked at (scene coordinates, relative to the mesh's centre).
    pub target: Vec3,
    /// Distance from the eye to the target.
    pub distance: f32,
    /// Rotation about the vertical axis, in radians.
    pub yaw: f32,
    /// Elevation, in radians, kept within (-pi/2, pi/2).
    pub pitch: f32,
    /// Radius of the scene, for the reset and the clip planes.
    pub radius: f32,
}

impl OrbitCamera {
    /// A camera that frames a sphere of `radius` around the origin.
    pub fn framing(radius: f32) -> Self {
        let radius = if radius.is_finite() && radius > 0.0 {
            radius
        } else {
            1.0
        };
        Self {
            target: Vec3::ZERO,
            distance: radius / (FOV_Y * 0.5).sin() * 1.05,
            yaw: 0.5,
            pitch: 0.3,
            radius,
        }
    }

    /// Back to the framing view.
    pub fn reset(&mut self) {
        *self = Self::framing(self.radius);
    }

    /// Eye position.
    pub fn eye(&self) -> Vec3 {
        let (sy, cy) = self.yaw.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        self.target + self.distance * Vec3::new(cp * sy, sp, cp * cy)
    }

    /// Turn by a drag of `dx`, `dy` pixels.
    pub fn orbit(&mut self, dx: f32, dy: f32) {
        self.yaw -= dx * 0.008;
        self.pitch = (self.pitch + dy * 0.008).clamp(-1.55, 1.55);
    }

    /// Move the target in the view plane by a drag of `dx`, `dy` pixels in a view
    /// `height` pixels high, so that the point under the cursor follows it.
    pub fn pan(&mut self, dx: f32, dy: f32, height: f32) {
        let view = self.view();
        let right = Vec3::new(view.x_axis.x, view.y_axis.x, view.z_axis.x);
        let up = Vec3::new(view.x_axis.y, view.y_axis.y, view.z_axis.y);
        let per_px = 2.0 * self.distance * (FOV_Y * 0.5).tan() / height.max(1.0);
        self.target += (-dx * right + dy * up) * per_px;
    }

    /// Zoom by `factor` (> 1 moves closer).
    pub fn zoom(&mut self, factor: f32) {
        if factor.is_finite() && factor > 0.0 {
            self.distance = (self.distance / factor).clamp(self.radius * 0.05, self.radius * 50.0);
        }
    }

    /// The view matrix.
    pub fn view(&self) -> Mat4 {
        glam::camera::rh::view::look_at_mat4(self.eye(), self.target, Vec3::Y)
    }

    /// Projection times view, for a viewport of the given aspect ratio (width / height).
    pub fn view_projection(&self, aspect: f32) -> Mat4 {
        let near = (self.distance - 2.0 * self.radius).max(self.distance * 0.01);
        let far = self.distance + 2.0 * self.radius;
        glam::camera::rh::proj::opengl::perspective(FOV_Y, aspect.max(1e-3), near, far)
            * self.view()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn framing_view_sees_the_whole_sphere() {
        let cam = OrbitCamera::framing(2.0);
        let m = cam.view_projection(1.0);
        for p in [Vec3::X, Vec3::Y, Vec3::Z, -Vec3::X, -Vec3::Y, -Vec3::Z] {
            let c = m.project_point3(p * 2.0);
            assert!(c.abs().max_element() <= 1.0, "{p} -> {c}");
        }
    }

    #[test]
    fn orbit_zoom_pan_and_reset() {
        let mut cam = OrbitCamera::framing(1.0);
        let start = cam;
        cam.orbit(100.0, 1000.0);
        assert!(cam.pitch <= 1.55);
        cam.zoom(2.0);
        assert!(cam.distance < start.distance);
        cam.zoom(1e-9);
        assert!(cam.distance <= 50.0);
        cam.pan(10.0, 0.0, 100.0);
        assert!(cam.target.length() > 0.0);
        cam.reset();
        assert_eq!(cam, start);
    }
}
