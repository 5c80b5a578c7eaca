//! A free-flying camera: position, yaw and pitch (no roll), moved by keys and turned by the
//! mouse. Until it moves it is exactly the scene's camera (roll and all), so a window's first
//! frame matches `voxgi render`.

use crate::scene::{Aabb, Camera};
use glam::{Mat4, Quat, Vec3};

#[derive(Clone, Debug)]
pub struct FlyCamera {
    start: Camera,
    pub position: Vec3,
    /// Turn about +Y, radians; 0 looks along -Z.
    pub yaw: f32,
    /// Up from the horizon, radians.
    pub pitch: f32,
    /// Metres per second.
    pub speed: f32,
    base_speed: f32,
    moved: bool,
}

/// Radians per pixel of mouse motion.
const LOOK_PER_PIXEL: f32 = 0.003;
const MAX_PITCH: f32 = 89.0 * std::f32::consts::PI / 180.0;

impl FlyCamera {
    /// Starts at `camera`, flying a quarter of the scene's diagonal per second.
    pub fn new(camera: &Camera, bounds: &Aabb) -> FlyCamera {
        let diagonal = bounds.extent().length();
        let base_speed = if diagonal.is_finite() && diagonal > 0.0 {
            0.25 * diagonal
        } else {
            1.0
        };
        let mut c = FlyCamera {
            start: camera.clone(),
            position: Vec3::ZERO,
            yaw: 0.0,
            pitch: 0.0,
            speed: base_speed,
            base_speed,
            moved: false,
        };
        c.reset();
        c
    }

    /// Back to the scene's camera and the starting speed.
    pub fn reset(&mut self) {
        let forward = -self.start.world.z_axis.truncate().normalize_or(Vec3::NEG_Z);
        self.position = self.start.eye();
        self.pitch = forward
            .y
            .clamp(-1.0, 1.0)
            .asin()
            .clamp(-MAX_PITCH, MAX_PITCH);
        self.yaw = (-forward.x).atan2(-forward.z);
        self.speed = self.base_speed;
        self.moved = false;
    }

    pub fn rotation(&self) -> Quat {
        Quat::from_rotation_y(self.yaw) * Quat::from_rotation_x(self.pitch)
    }

    /// Where it looks.
    pub fn forward(&self) -> Vec3 {
        self.rotation() * Vec3::NEG_Z
    }

    /// The camera to render with.
    pub fn camera(&self) -> Camera {
        let mut c = self.start.clone();
        if self.moved {
            c.world = Mat4::from_rotation_translation(self.rotation(), self.position);
        }
        c
    }

    /// Flies for `dt` seconds along `dir`: x right, y world up, z forward (each -1..1).
    pub fn fly(&mut self, dir: Vec3, dt: f32, fast: bool) {
        if dir == Vec3::ZERO || dt <= 0.0 {
            return;
        }
        let r = self.rotation();
        let v = r * Vec3::X * dir.x + Vec3::Y * dir.y + r * Vec3::NEG_Z * dir.z;
        let speed = self.speed * if fast { 4.0 } else { 1.0 };
        self.position += v.normalize_or_zero() * speed * dt;
        self.moved = true;
    }

    /// Turns by a mouse motion of (dx, dy) pixels (right and down positive).
    pub fn look(&mut self, dx: f32, dy: f32) {
        if dx == 0.0 && dy == 0.0 {
            return;
        }
        self.yaw -= dx * LOOK_PER_PIXEL;
        self.pitch = (self.pitch - dy * LOOK_PER_PIXEL).clamp(-MAX_PITCH, MAX_PITCH);
        self.moved = true;
    }

    /// Scroll steps: each multiplies the speed by 1.25 (negative divides).
    pub fn scroll(&mut self, steps: f32) {
        self.speed =
            (self.speed * 1.25f32.powf(steps)).clamp(1e-4 * self.base_speed, 1e4 * self.base_speed);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn looking(eye: Vec3, at: Vec3) -> Camera {
        Camera {
            name: None,
            world: Mat4::look_at_rh(eye, at, Vec3::Y).inverse(),
            yfov: 0.7,
            znear: 0.1,
            zfar: 100.0,
            is_default: false,
        }
    }

    fn bounds() -> Aabb {
        Aabb {
            min: Vec3::splat(-1.0),
            max: Vec3::splat(1.0),
        }
    }

    #[test]
    fn starts_as_the_scene_camera_and_resets_to_it() {
        let cam = looking(Vec3::new(3.0, 2.0, 5.0), Vec3::ZERO);
        let mut fly = FlyCamera::new(&cam, &bounds());
        assert_eq!(fly.camera().world, cam.world);
        // Its yaw and pitch reproduce the scene camera's view direction.
        let want = (Vec3::ZERO - cam.eye()).normalize();
        assert!(
            fly.forward().distance(want) < 1e-5,
            "{:?} vs {want:?}",
            fly.forward()
        );
        let rebuilt = Mat4::from_rotation_translation(fly.rotation(), fly.position);
        assert!(rebuilt.abs_diff_eq(cam.world, 1e-5));
        fly.fly(Vec3::Z, 1.0, false);
        fly.look(10.0, 5.0);
        assert_ne!(fly.camera().world, cam.world);
        fly.reset();
        assert_eq!(fly.camera().world, cam.world);
    }

    #[test]
    fn flies_forward_and_strafes_right_at_its_speed() {
        let cam = looking(Vec3::ZERO, Vec3::new(0.0, 0.0, -1.0));
        let mut fly = FlyCamera::new(&cam, &bounds());
        let speed = fly.speed;
        assert!((speed - 0.25 * 12f32.sqrt()).abs() < 1e-5);
        fly.fly(Vec3::Z, 2.0, false);
        assert!(fly.position.distance(Vec3::new(0.0, 0.0, -2.0 * speed)) < 1e-5);
        fly.fly(Vec3::X, 1.0, true);
        assert!((fly.position.x - 4.0 * speed).abs() < 1e-5);
        // Turning right by a quarter turn of mouse motion makes forward +X.
        fly.look(std::f32::consts::FRAC_PI_2 / LOOK_PER_PIXEL, 0.0);
        assert!(
            fly.forward().distance(Vec3::X) < 1e-4,
            "{:?}",
            fly.forward()
        );
        // Looking down is clamped short of straight down.
        fly.look(0.0, 1e6);
        assert!(fly.pitch >= -MAX_PITCH - 1e-6 && fly.forward().y < -0.99);
        fly.scroll(2.0);
        assert!((fly.speed - speed * 1.5625).abs() < 1e-4);
    }
}
