//! An orbit camera that can also fly: it looks at `target` from `distance` away, turned by `yaw`
//! about the vertical and tilted down by `pitch`.

use glam::{Mat4, Vec3};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    pub target: Vec3,
    /// Radians about +y; 0 looks along -z.
    pub yaw: f32,
    /// Radians above the horizon the eye sits at; kept within (−89°, 89°).
    pub pitch: f32,
    pub distance: f32,
    /// Vertical field of view in radians.
    pub fov_y: f32,
}

const PITCH_LIMIT: f32 = 89.0 * std::f32::consts::PI / 180.0;
const MIN_DISTANCE: f32 = 0.2;
const MAX_DISTANCE: f32 = 2000.0;

impl Camera {
    pub fn new(target: Vec3, yaw_deg: f32, pitch_deg: f32, distance: f32) -> Self {
        Camera {
            target,
            yaw: yaw_deg.to_radians(),
            pitch: pitch_deg.to_radians().clamp(-PITCH_LIMIT, PITCH_LIMIT),
            distance: distance.clamp(MIN_DISTANCE, MAX_DISTANCE),
            fov_y: 50f32.to_radians(),
        }
    }

    /// Unit vector from the eye towards the target.
    pub fn forward(&self) -> Vec3 {
        let (sy, cy) = self.yaw.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        Vec3::new(-sy * cp, -sp, -cy * cp)
    }

    pub fn eye(&self) -> Vec3 {
        self.target - self.forward() * self.distance
    }

    pub fn view(&self) -> Mat4 {
        glam::camera::rh::view::look_at_mat4(self.eye(), self.target, Vec3::Y)
    }

    pub fn near_far(&self) -> (f32, f32) {
        let near = (self.distance * 0.01).clamp(0.02, 0.5);
        (near, 3000.0)
    }

    /// Projection with depth 0..1, as wgpu wants.
    pub fn proj(&self, aspect: f32) -> Mat4 {
        let (near, far) = self.near_far();
        glam::camera::rh::proj::directx::perspective(self.fov_y, aspect.max(1e-3), near, far)
    }

    /// Turns the camera around its target by the given angles in radians.
    pub fn orbit(&mut self, d_yaw: f32, d_pitch: f32) {
        self.yaw = (self.yaw + d_yaw).rem_euclid(std::f32::consts::TAU);
        self.pitch = (self.pitch + d_pitch).clamp(-PITCH_LIMIT, PITCH_LIMIT);
    }

    /// Moves closer (factor < 1) or further away.
    pub fn zoom(&mut self, factor: f32) {
        self.distance = (self.distance * factor).clamp(MIN_DISTANCE, MAX_DISTANCE);
    }

    /// Slides target and eye together in the view plane; `dx`, `dy` in fractions of the view
    /// height, so a drag across the screen moves by what the screen shows.
    pub fn pan(&mut self, dx: f32, dy: f32) {
        let f = self.forward();
        let right = f.cross(Vec3::Y).normalize_or(Vec3::X);
        let up = right.cross(f);
        let scale = 2.0 * self.distance * (self.fov_y * 0.5).tan();
        self.target += (-right * dx + up * dy) * scale;
    }

    /// Flies: `forward` along the view direction flattened onto the ground, `right` sideways,
    /// `up` vertically, each in metres.
    pub fn fly(&mut self, forward: f32, right: f32, up: f32) {
        let f = self.forward();
        let flat = Vec3::new(f.x, 0.0, f.z).normalize_or(Vec3::NEG_Z);
        let side = flat.cross(Vec3::Y);
        self.target += flat * forward + side * right + Vec3::Y * up;
        self.target.y = self.target.y.max(0.0);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eye_is_distance_from_target_and_looks_at_it() {
        let c = Camera::new(Vec3::new(1.0, 2.0, 3.0), 30.0, 20.0, 10.0);
        assert!((c.eye().distance(c.target) - 10.0).abs() < 1e-4);
        assert!(c.eye().y > c.target.y);
        let p = c.proj(1.5) * c.view() * c.target.extend(1.0);
        assert!((p.x / p.w).abs() < 1e-5 && (p.y / p.w).abs() < 1e-5);
        assert!(p.z / p.w > 0.0 && p.z / p.w < 1.0);
    }

    #[test]
    fn pitch_is_clamped_and_fly_stays_above_ground() {
        let mut c = Camera::new(Vec3::ZERO, 0.0, 0.0, 5.0);
        c.orbit(0.0, 10.0);
        assert!(c.pitch < std::f32::consts::FRAC_PI_2);
        c.fly(0.0, 0.0, -5.0);
        assert_eq!(c.target.y, 0.0);
        c.fly(2.0, 0.0, 0.0);
        assert!(c.target.length() > 1.9);
    }
}
