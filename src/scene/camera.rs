//! Pinhole perspective camera: origin, target, up, vertical field of view, resolution.

use crate::math::{Ray, Vec3};

#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CameraDesc {
    pub origin: [f32; 3],
    pub target: [f32; 3],
    pub up: [f32; 3],
    /// Vertical field of view in degrees.
    pub fov: f32,
}

impl CameraDesc {
    /// Parse "ox,oy,oz,tx,ty,tz,ux,uy,uz,fov" (the `--camera` option).
    pub fn parse(s: &str) -> Result<CameraDesc, String> {
        let v: Vec<f32> = s
            .split([',', ' '])
            .filter(|t| !t.is_empty())
            .map(|t| {
                t.parse::<f32>()
                    .map_err(|_| format!("--camera: {t:?} is not a number"))
            })
            .collect::<Result<_, _>>()?;
        if v.len() != 10 {
            return Err(format!(
                "--camera: expected 10 numbers ox,oy,oz,tx,ty,tz,ux,uy,uz,fov, got {}",
                v.len()
            ));
        }
        let c = CameraDesc {
            origin: [v[0], v[1], v[2]],
            target: [v[3], v[4], v[5]],
            up: [v[6], v[7], v[8]],
            fov: v[9],
        };
        c.validate().map_err(|e| format!("--camera: {e}"))?;
        Ok(c)
    }

    pub fn validate(&self) -> Result<(), String> {
        let o = Vec3::from(self.origin);
        let t = Vec3::from(self.target);
        let u = Vec3::from(self.up);
        if !(o.is_finite() && t.is_finite() && u.is_finite() && self.fov.is_finite()) {
            return Err("camera values must be finite".into());
        }
        if (t - o).length() == 0.0 {
            return Err("camera origin and target coincide".into());
        }
        if (t - o).normalize().cross(u).length() < 1e-6 {
            return Err("camera up vector is parallel to the view direction (or zero)".into());
        }
        if !(self.fov > 0.0 && self.fov < 180.0) {
            return Err(format!(
                "field of view {} must be in (0, 180) degrees",
                self.fov
            ));
        }
        Ok(())
    }
}

/// A camera ready to generate rays for a given resolution.
#[derive(Clone, Copy, Debug)]
pub struct Camera {
    pub desc: CameraDesc,
    pub width: u32,
    pub height: u32,
    origin: Vec3,
    forward: Vec3,
    right: Vec3,
    up: Vec3,
    tan_half: f32,
    aspect: f32,
}

impl Camera {
    pub fn new(desc: CameraDesc, width: u32, height: u32) -> Camera {
        let origin = Vec3::from(desc.origin);
        let forward = (Vec3::from(desc.target) - origin).normalize();
        let right = forward.cross(Vec3::from(desc.up)).normalize();
        let up = right.cross(forward);
        Camera {
            desc,
            width,
            height,
            origin,
            forward,
            right,
            up,
            tan_half: (desc.fov.to_radians() * 0.5).tan(),
            aspect: width as f32 / height as f32,
        }
    }

    /// Ray through film position (x, y) in pixels, y = 0 at the top of the image.
    #[inline]
    pub fn ray(&self, x: f32, y: f32) -> Ray {
        let sx = (2.0 * x / self.width as f32 - 1.0) * self.tan_half * self.aspect;
        let sy = (1.0 - 2.0 * y / self.height as f32) * self.tan_half;
        let d = (self.forward + sx * self.right + sy * self.up).normalize();
        Ray::new(self.origin, d)
    }
}
