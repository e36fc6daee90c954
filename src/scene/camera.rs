//! Pinhole perspective camera: origin, target, up, vertical field of view, resolution; and
//! the camera of a scene that gives none (`default_camera`: framing the bounds, or inside a
//! closed room).
//!
//! Camera importance for light tracing and bidirectional path tracing (Veach's thesis,
//! section 10.2; pbrt-v4 `PerspectiveCamera::We`): the film is the plane at unit distance
//! along the view direction, of area A = (2 tan(fov/2) aspect)(2 tan(fov/2)). A camera ray
//! through a uniform film point has solid-angle density p(w) = 1 / (A cos^3 theta), and
//! W_e(w) = 1 / (A cos^4 theta): with one light path per camera sample, the splats a pixel
//! receives divided by its sample count estimate the same pixel value as its camera rays
//! (the mean radiance over the pixel). The position is a Dirac point (pdf 1 by convention).

use crate::accel::Bvh;
use crate::math::{Bounds3, Ray, Vec2, Vec3};

mod filter;
pub use filter::PixelFilter;

#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CameraDesc {
    pub origin: [f32; 3],
    pub target: [f32; 3],
    pub up: [f32; 3],
    /// Field of view in degrees, along `fov_axis` of the film.
    pub fov: f32,
    /// The film extent `fov` spans (vertical unless a Mitsuba sensor's `fov_axis` says
    /// otherwise): resolved against the resolution the render runs at, so that `--res`
    /// keeps a Mitsuba scene's horizontal field of view as Mitsuba's `-D resx=..` does.
    #[serde(default)]
    pub fov_axis: FovAxis,
    /// How the film maps to rays: a pinhole (kalos' default) or parallel rays.
    #[serde(default)]
    pub projection: Projection,
    /// The film's reconstruction filter (a box unless a Mitsuba film names one or takes
    /// Mitsuba's default Gaussian).
    #[serde(default)]
    pub filter: PixelFilter,
}

/// How a camera maps film positions to rays.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(tag = "type", rename_all = "lowercase", deny_unknown_fields)]
pub enum Projection {
    /// A pinhole at `origin` with the field of view `fov`.
    #[default]
    Perspective,
    /// Parallel rays along the view direction, starting on the plane through `origin`
    /// (Mitsuba's `orthographic` sensor): the film covers [-1, 1] x [-1/aspect, 1/aspect]
    /// (aspect = width / height) of the sensor's local x and y, scaled by the lengths of
    /// its `to_world` axes, `scale_x` and `scale_y` world units. `fov` is not used.
    Orthographic { scale_x: f32, scale_y: f32 },
}

impl Default for CameraDesc {
    /// A pinhole at the origin looking along -z, 45 degrees vertically, box filter.
    fn default() -> CameraDesc {
        CameraDesc {
            origin: [0.0; 3],
            target: [0.0, 0.0, -1.0],
            up: [0.0, 1.0, 0.0],
            fov: 45.0,
            fov_axis: FovAxis::Y,
            projection: Projection::Perspective,
            filter: PixelFilter::Box,
        }
    }
}

/// Which extent of the film a field of view spans (Mitsuba's `fov_axis`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum FovAxis {
    X,
    #[default]
    Y,
    Diagonal,
    /// The smaller of width and height.
    Smaller,
    /// The larger of width and height.
    Larger,
}

impl FovAxis {
    /// Mitsuba's names: x, y, diagonal, smaller, larger.
    pub fn parse(s: &str) -> Option<FovAxis> {
        Some(match s {
            "x" => FovAxis::X,
            "y" => FovAxis::Y,
            "diagonal" => FovAxis::Diagonal,
            "smaller" => FovAxis::Smaller,
            "larger" => FovAxis::Larger,
            _ => return None,
        })
    }
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
            fov_axis: FovAxis::Y,
            ..Default::default()
        };
        c.validate().map_err(|e| format!("--camera: {e}"))?;
        Ok(c)
    }

    /// tan of half the vertical field of view on a `width` x `height` film.
    pub fn tan_half_vertical(&self, width: u32, height: u32) -> f32 {
        let t = (self.fov.to_radians() * 0.5).tan();
        let (w, h) = (width.max(1) as f32, height.max(1) as f32);
        match self.fov_axis {
            FovAxis::Y => t,
            FovAxis::X => t * h / w,
            FovAxis::Diagonal => t * h / w.hypot(h),
            FovAxis::Smaller if w < h => t * h / w,
            FovAxis::Larger if w > h => t * h / w,
            FovAxis::Smaller | FovAxis::Larger => t,
        }
    }

    /// The same camera with its field of view given vertically for a `width` x `height`
    /// film (as `--camera` takes it).
    pub fn vertical(&self, width: u32, height: u32) -> CameraDesc {
        CameraDesc {
            fov: (2.0 * self.tan_half_vertical(width, height).atan()).to_degrees(),
            fov_axis: FovAxis::Y,
            ..*self
        }
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
    /// Half the film's width and height in world units, for parallel rays.
    ortho: Option<(f32, f32)>,
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
            tan_half: desc.tan_half_vertical(width, height),
            aspect: width as f32 / height as f32,
            ortho: match desc.projection {
                Projection::Perspective => None,
                Projection::Orthographic { scale_x, scale_y } => {
                    Some((scale_x, scale_y * height as f32 / width as f32))
                }
            },
        }
    }

    /// Film position (pixels) of a camera sample of pixel (x, y) from uniform `u`: drawn
    /// from the film's reconstruction filter around the pixel (`x + u` for the box).
    #[inline]
    pub fn film_position(&self, x: u32, y: u32, u: Vec2) -> Vec2 {
        let f = self.desc.filter;
        Vec2::new(
            f.film_coordinate(x, self.width, u.x),
            f.film_coordinate(y, self.height, u.y),
        )
    }

    /// Does the camera have a pinhole (light paths can be connected to it)?
    #[inline]
    pub fn is_pinhole(&self) -> bool {
        self.ortho.is_none()
    }

    /// Ray through film position (x, y) in pixels, y = 0 at the top of the image.
    #[inline]
    pub fn ray(&self, x: f32, y: f32) -> Ray {
        if let Some((hw, hh)) = self.ortho {
            let sx = (2.0 * x / self.width as f32 - 1.0) * hw;
            let sy = (1.0 - 2.0 * y / self.height as f32) * hh;
            return Ray::new(self.origin + sx * self.right + sy * self.up, self.forward);
        }
        let sx = (2.0 * x / self.width as f32 - 1.0) * self.tan_half * self.aspect;
        let sy = (1.0 - 2.0 * y / self.height as f32) * self.tan_half;
        let d = (self.forward + sx * self.right + sy * self.up).normalize();
        Ray::new(self.origin, d)
    }
}

/// A direction sampled from a reference point towards the camera (`Camera::sample_wi`).
#[derive(Clone, Copy, Debug)]
pub struct CameraWi {
    /// Unit direction from the reference point to the camera.
    pub wi: Vec3,
    /// Distance from the reference point to the camera.
    pub dist: f32,
    /// Film position the ray from the camera to the point lands on.
    pub raster: Vec2,
    /// W_e of that ray.
    pub we: f32,
    /// Density of the camera position, converted to solid angle at the reference point:
    /// dist^2 / cos theta (the camera position is a Dirac point).
    pub pdf: f32,
}

impl Camera {
    /// The pinhole.
    #[inline]
    pub fn position(&self) -> Vec3 {
        self.origin
    }

    /// Unit view direction (the normal of the film plane).
    #[inline]
    pub fn forward(&self) -> Vec3 {
        self.forward
    }

    /// A: area of the film plane at unit distance.
    #[inline]
    pub fn film_area(&self) -> f32 {
        4.0 * self.tan_half * self.tan_half * self.aspect
    }

    /// Film position (pixels, y = 0 at the top) of the camera ray along world direction `d`
    /// (any length), the inverse of `ray`; None if it leaves the image.
    #[inline]
    pub fn raster(&self, d: Vec3) -> Option<Vec2> {
        let z = d.dot(self.forward);
        // parallel rays: no direction reaches the film through a point
        if z <= 0.0 || self.ortho.is_some() {
            return None;
        }
        let sx = d.dot(self.right) / z;
        let sy = d.dot(self.up) / z;
        let x = (sx / (self.tan_half * self.aspect) + 1.0) * 0.5 * self.width as f32;
        let y = (1.0 - sy / self.tan_half) * 0.5 * self.height as f32;
        let inside = x >= 0.0 && x < self.width as f32 && y >= 0.0 && y < self.height as f32;
        inside.then_some(Vec2::new(x, y))
    }

    /// W_e(w) = 1 / (A cos^4 theta) of the camera ray along unit direction `w` (0 outside
    /// the image).
    #[inline]
    pub fn we(&self, w: Vec3) -> f32 {
        if self.raster(w).is_none() {
            return 0.0;
        }
        let c = w.dot(self.forward);
        1.0 / (self.film_area() * c * c * c * c)
    }

    /// Densities of `ray`'s sampling for unit direction `w`: (position, solid angle) =
    /// (1, 1 / (A cos^3 theta)), or (1, 0) outside the image.
    #[inline]
    pub fn pdf_we(&self, w: Vec3) -> (f32, f32) {
        if self.raster(w).is_none() {
            return (1.0, 0.0);
        }
        let c = w.dot(self.forward);
        (1.0, 1.0 / (self.film_area() * c * c * c))
    }

    /// Connect reference point `p` to the camera: the direction, the film position, W_e
    /// and the density of the camera position in solid angle at `p`. None if `p` is
    /// outside the view (or at the pinhole).
    #[inline]
    pub fn sample_wi(&self, p: Vec3) -> Option<CameraWi> {
        let d = self.origin - p;
        let dist2 = d.length_squared();
        if dist2 <= 0.0 || !dist2.is_finite() {
            return None;
        }
        let dist = dist2.sqrt();
        let wi = d / dist;
        let raster = self.raster(-wi)?;
        let cos = (-wi).dot(self.forward);
        let we = 1.0 / (self.film_area() * cos * cos * cos * cos);
        Some(CameraWi {
            wi,
            dist,
            raster,
            we,
            pdf: dist2 / cos,
        })
    }
}

/// A camera on +z of the bounds' centre looking at it, 45 degrees vertical, far enough
/// back to frame the bounding sphere.
pub fn framing_camera(b: &Bounds3) -> CameraDesc {
    let (c, r) = if b.is_empty() {
        (Vec3::ZERO, 1.0)
    } else {
        (b.centroid(), (b.diagonal() * 0.5).max(1e-3))
    };
    let fov = 45.0f32;
    let dist = r / (fov.to_radians() * 0.5).tan() * 1.1;
    CameraDesc {
        origin: (c + Vec3::new(0.0, 0.0, dist)).into(),
        target: c.into(),
        up: [0.0, 1.0, 0.0],
        fov,
        fov_axis: FovAxis::Y,
        ..Default::default()
    }
}

/// The camera kalos chose for a scene that gives none, and why.
#[derive(Clone, Debug)]
pub struct DefaultCamera {
    pub desc: CameraDesc,
    /// How it was chosen, for `kalos info` ("framing the bounds from +z", ...).
    pub how: String,
    /// A warning for the user (the camera was moved inside, or may see nothing).
    pub warning: Option<String>,
}

/// Unit directions spread evenly over the sphere (a Fibonacci lattice).
fn sphere_directions(n: usize) -> Vec<Vec3> {
    let golden = std::f32::consts::PI * (3.0 - 5f32.sqrt());
    (0..n)
        .map(|i| {
            let z = 1.0 - 2.0 * (i as f32 + 0.5) / n as f32;
            let r = (1.0 - z * z).max(0.0).sqrt();
            let phi = golden * i as f32;
            Vec3::new(r * phi.cos(), r * phi.sin(), z)
        })
        .collect()
}

/// What the default camera needs of the scene's triangles to judge a view: each
/// triangle's material and whether that material emits.
pub struct Surfaces<'a> {
    pub material: &'a [u32],
    pub emits: &'a [bool],
}

/// What a candidate view sees on a 16x16 grid of pilot rays.
#[derive(Clone, Copy, Debug, PartialEq)]
struct View {
    /// Distinct non-emitting materials hit.
    materials: usize,
    /// Share of the rays that hit an emitter.
    emitter_share: f32,
}

impl View {
    fn describe(&self) -> String {
        format!(
            "{} materials, emitters {:.0}% of the frame",
            self.materials,
            100.0 * self.emitter_share
        )
    }
}

fn view_of(bvh: &Bvh, desc: &CameraDesc, s: &Surfaces) -> View {
    const N: u32 = 16;
    let cam = Camera::new(*desc, N, N);
    let mut seen = std::collections::BTreeSet::new();
    let mut emitters = 0;
    for y in 0..N {
        for x in 0..N {
            let r = cam.ray(x as f32 + 0.5, y as f32 + 0.5);
            let Some(h) = bvh.intersect(&r, f32::INFINITY) else {
                continue;
            };
            let m = s.material.get(h.prim as usize).copied().unwrap_or(0);
            if s.emits.get(m as usize).copied().unwrap_or(false) {
                emitters += 1;
            } else {
                seen.insert(m);
            }
        }
    }
    View {
        materials: seen.len(),
        emitter_share: emitters as f32 / (N * N) as f32,
    }
}

/// Is `to` visible from `from` (nothing in between, up to a small margin)?
fn visible(bvh: &Bvh, from: Vec3, to: Vec3) -> bool {
    let d = to - from;
    let len = d.length();
    if len <= 1e-6 {
        return true;
    }
    !bvh.occluded(&Ray::new(from, d / len), len * 0.999)
}

/// The default camera of a scene without one. Normally it frames the bounds from +z
/// (`framing_camera`). When that camera would see nothing lit — every ray it casts meets
/// the outside of a closed room whose lights are inside — the camera is placed inside:
/// at the point of a 7x7x7 grid over the bounds that is enclosed (98% of 64 rays hit
/// geometry), sees a light, and is farthest from any surface. From there it looks along
/// the horizontal axis (y is up) whose view shows the most of the room: each of +x, -x,
/// +z and -z, from three quarters of the way back to the wall behind, 60 degrees
/// vertical, casts a 16x16 grid of pilot rays; the view that hits the most distinct
/// materials wins, unless emitters fill more than a fifth of its frame (a window or a
/// light panel seen head on), ties to the longer view. `how` says what each view saw. If no such point exists the framing camera stays and
/// the warning says how to give one (`--camera`).
///
/// `lights`: points on the emitters (triangle centroids, point lights); `environment`:
/// the scene has light from far away (then the outside is lit and the camera stays).
pub fn default_camera(
    bvh: &Bvh,
    bounds: &Bounds3,
    lights: &[Vec3],
    environment: bool,
    surfaces: &Surfaces,
) -> DefaultCamera {
    let outside = framing_camera(bounds);
    let framing = DefaultCamera {
        desc: outside,
        how: "default: framing the bounds from +z".into(),
        warning: None,
    };
    if bounds.is_empty() || environment || lights.is_empty() {
        return framing;
    }
    // does the framing camera see anything lit? (a light seen directly, or a surface
    // point from which a light is visible)
    let eps = 1e-4 * bounds.diagonal().max(1e-3);
    let cam = Camera::new(outside, 16, 16);
    let step = (lights.len() / 16).max(1);
    let lit_sample: Vec<Vec3> = lights.iter().step_by(step).copied().collect();
    let mut sees_lit = false;
    'rays: for y in 0..16 {
        for x in 0..16 {
            let r = cam.ray(x as f32 + 0.5, y as f32 + 0.5);
            let Some(h) = bvh.intersect(&r, f32::INFINITY) else {
                continue;
            };
            let p = r.at(h.t) - r.d * eps;
            if lit_sample.iter().any(|&l| visible(bvh, p, l)) {
                sees_lit = true;
                break 'rays;
            }
        }
    }
    if sees_lit {
        return framing;
    }
    // the roomiest enclosed point that sees a light
    let dirs = sphere_directions(64);
    let ext = bounds.extent();
    let n = 7;
    let mut best: Option<(f32, Vec3)> = None;
    for k in 0..n * n * n {
        let (i, j, l) = (k % n, (k / n) % n, k / (n * n));
        let f = |a: usize| (a as f32 + 0.5) / n as f32;
        let p = bounds.min + ext * Vec3::new(f(i), f(j), f(l));
        let mut hits = 0;
        let mut clearance = f32::INFINITY;
        for &d in &dirs {
            if let Some(h) = bvh.intersect(&Ray::new(p, d), f32::INFINITY) {
                hits += 1;
                clearance = clearance.min(h.t);
            }
        }
        if (hits as f32) < 0.98 * dirs.len() as f32 {
            continue;
        }
        if !lit_sample.iter().any(|&lp| visible(bvh, p, lp)) {
            continue;
        }
        if best.is_none_or(|(c, _)| clearance > c) {
            best = Some((clearance, p));
        }
    }
    let fix = "give a camera with --camera ox,oy,oz,tx,ty,tz,ux,uy,uz,fov";
    let Some((_, p)) = best else {
        return DefaultCamera {
            warning: Some(format!(
                "no camera given, and the default one (outside the bounds, looking at their centre from +z) sees no lit surface; no enclosed point that sees a light was found to move it to: {fix}"
            )),
            ..framing
        };
    };
    let dist = |d: Vec3| {
        bvh.intersect(&Ray::new(p, d), f32::INFINITY)
            .map(|h| h.t)
            .unwrap_or(0.0)
    };
    let name = |d: Vec3| match (d.x, d.z) {
        (x, _) if x > 0.5 => "+x",
        (x, _) if x < -0.5 => "-x",
        (_, z) if z > 0.5 => "+z",
        _ => "-z",
    };
    // Each horizontal direction from three quarters of the way back to the wall behind,
    // judged by what its pilot rays see: most distinct materials (the room's contents),
    // unless emitters fill more than a fifth of the frame (a window or lamp panel seen
    // head on); ties go to the longer view.
    let candidates = [Vec3::X, -Vec3::X, Vec3::Z, -Vec3::Z].map(|dir| {
        let origin = p - dir * 0.75 * dist(-dir);
        let desc = CameraDesc {
            origin: origin.into(),
            target: (origin + dir).into(),
            up: [0.0, 1.0, 0.0],
            fov: 60.0,
            fov_axis: FovAxis::Y,
            ..Default::default()
        };
        let view = view_of(bvh, &desc, surfaces);
        (dir, desc, view, dist(dir))
    });
    let rank = |v: &View, depth: f32| (v.emitter_share <= 0.2, v.materials, depth);
    let (dir, desc, view, _) = candidates
        .iter()
        .max_by(|a, b| {
            rank(&a.2, a.3)
                .partial_cmp(&rank(&b.2, b.3))
                .unwrap_or(std::cmp::Ordering::Equal)
        })
        .cloned()
        .expect("four candidates");
    let origin = Vec3::from(desc.origin);
    let others: Vec<String> = candidates
        .iter()
        .filter(|c| c.0 != dir)
        .map(|c| format!("{} {}", name(c.0), c.2.describe()))
        .collect();
    let how = format!(
        "default: inside the closed room, looking along {}: it sees {} (the others: {})",
        name(dir),
        view.describe(),
        others.join("; ")
    );
    DefaultCamera {
        warning: Some(format!(
            "no camera given, and the bounds enclose a closed room (the default camera outside would see only its walls): the camera is placed inside at ({:.3}, {:.3}, {:.3}) looking along {}, the view that sees the most ({}; {}; `kalos info` prints it)",
            origin.x,
            origin.y,
            origin.z,
            name(dir),
            view.describe(),
            "--camera ox,oy,oz,tx,ty,tz,ux,uy,uz,fov chooses another"
        )),
        desc,
        how,
    }
}

impl CameraDesc {
    /// What an estimator that connects light paths to the camera (BDPT) makes of it: an
    /// error for parallel rays (no light path reaches such a film through a point), a
    /// warning for a reconstruction filter other than the box (its camera rays and light
    /// splats keep to their pixel, so it renders with the box).
    pub fn for_light_paths(&self) -> Result<Option<String>, String> {
        if let Projection::Orthographic { .. } = self.projection {
            return Err(
                "the orthographic camera takes no light paths: render it with --integrator path"
                    .into(),
            );
        }
        Ok((!self.filter.is_box()).then(|| {
            format!(
                "the film's {} reconstruction filter is not applied by BDPT: it renders with the box filter (--integrator path applies it)",
                self.filter.name()
            )
        }))
    }

    /// The camera given on the command line (`--camera`, a pinhole) over the scene's film:
    /// the scene's reconstruction filter stays.
    pub fn on_film_of(self, scene: &CameraDesc) -> CameraDesc {
        CameraDesc {
            filter: scene.filter,
            ..self
        }
    }

    /// The camera as a `--camera` value (its field of view vertical: see [`Self::vertical`]).
    pub fn to_arg(&self) -> String {
        let v = [
            self.origin[0],
            self.origin[1],
            self.origin[2],
            self.target[0],
            self.target[1],
            self.target[2],
            self.up[0],
            self.up[1],
            self.up[2],
            self.fov,
        ];
        v.iter()
            .map(|x| format!("{}", (x * 1e4).round() / 1e4))
            .collect::<Vec<_>>()
            .join(",")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::chi2::{assert_chi2, chi2_sphere, TestRng};

    fn cam(w: u32, h: u32) -> Camera {
        Camera::new(
            CameraDesc {
                origin: [0.3, -0.2, 1.5],
                target: [-0.1, 0.4, -1.0],
                up: [0.0, 1.0, 0.0],
                fov: 60.0,
                fov_axis: FovAxis::Y,
                ..Default::default()
            },
            w,
            h,
        )
    }

    #[test]
    fn raster_inverts_ray() {
        let c = cam(40, 25);
        let mut rng = TestRng::new(5);
        for _ in 0..1000 {
            let (x, y) = (rng.next_f32() * 40.0, rng.next_f32() * 25.0);
            let r = c.raster(c.ray(x, y).d).unwrap();
            assert!(
                (r.x - x).abs() < 1e-3 && (r.y - y).abs() < 1e-3,
                "{x} {y} {r}"
            );
        }
        assert!(c.raster(-c.forward()).is_none());
        assert!(c.raster(c.ray(-0.5, 3.0).d).is_none());
        assert!(c.raster(c.ray(3.0, 25.5).d).is_none());
        // pixel (0, 0) is the top left: up is towards y = 0
        let top = c.raster(c.forward() + 0.1 * c.up).unwrap();
        assert!(top.y < 12.5 && (top.x - 20.0).abs() < 1e-3);
    }

    #[test]
    fn chi2_camera_ray_directions() {
        let c = cam(32, 24);
        let r = chi2_sphere(
            |_, u| Some(c.ray(u.x * 32.0, u.y * 24.0).d),
            |w| c.pdf_we(w).1,
            300_000,
            11,
        );
        assert_chi2("camera rays", &r);
        assert!((r.pdf_integral - 1.0).abs() < 1e-2, "{}", r.pdf_integral);
    }

    #[test]
    fn importance_integrates_to_one_over_the_image() {
        // integral of W_e cos theta dw over the image = 1: the ratio W_e cos / p = 1 for
        // every camera ray, and sample_wi's W_e / pdf is the same per unit area.
        let c = cam(30, 20);
        let mut rng = TestRng::new(9);
        for _ in 0..200 {
            let d = c.ray(rng.next_f32() * 30.0, rng.next_f32() * 20.0).d;
            let ratio = c.we(d) * d.dot(c.forward()) / c.pdf_we(d).1;
            assert!((ratio - 1.0).abs() < 1e-4, "{ratio}");
            let p = c.position() + d * (0.5 + 3.0 * rng.next_f32());
            let s = c.sample_wi(p).unwrap();
            assert!((s.wi + d).length() < 1e-4);
            assert!((s.we - c.we(d)).abs() <= 1e-4 * s.we);
            let r = c.raster(d).unwrap();
            assert!((s.raster - r).length() < 1e-3);
        }
    }

    /// A closed 6 x 3 x 4 room (x, y, z) whose +x wall is one lit panel and whose -z
    /// side holds three boxes of their own materials: the longest axis looks at the
    /// panel, the view that shows the room's contents looks along -z.
    #[test]
    fn the_interior_camera_looks_at_the_contents_not_at_a_lit_wall() {
        let mut tris: Vec<[Vec3; 3]> = Vec::new();
        let mut material = Vec::new();
        let mut quad = |c: [Vec3; 4], m: u32| {
            tris.push([c[0], c[1], c[2]]);
            tris.push([c[0], c[2], c[3]]);
            material.extend([m, m]);
        };
        let (x, y, z) = (3.0, 3.0, 2.0);
        let v = Vec3::new;
        // walls (material 0), the +x wall lit (material 1)
        quad([v(-x, 0., -z), v(-x, 0., z), v(x, 0., z), v(x, 0., -z)], 0);
        quad([v(-x, y, -z), v(x, y, -z), v(x, y, z), v(-x, y, z)], 0);
        quad([v(-x, 0., -z), v(x, 0., -z), v(x, y, -z), v(-x, y, -z)], 0);
        quad([v(-x, 0., z), v(-x, y, z), v(x, y, z), v(x, 0., z)], 0);
        quad([v(-x, 0., -z), v(-x, y, -z), v(-x, y, z), v(-x, 0., z)], 0);
        quad([v(x, 0., -z), v(x, 0., z), v(x, y, z), v(x, y, -z)], 1);
        // three upright boards near the -z wall, materials 2, 3, 4
        for (k, cx) in [-1.5f32, 0.0, 1.5].into_iter().enumerate() {
            let zz = -z + 0.3;
            quad(
                [
                    v(cx - 0.4, 0., zz),
                    v(cx + 0.4, 0., zz),
                    v(cx + 0.4, 1.2, zz),
                    v(cx - 0.4, 1.2, zz),
                ],
                2 + k as u32,
            );
        }
        let bvh = Bvh::build(&tris);
        let mut bounds = Bounds3::default();
        tris.iter().flatten().for_each(|&p| bounds.grow(p));
        let lights: Vec<Vec3> = tris
            .iter()
            .zip(&material)
            .filter(|(_, &m)| m == 1)
            .map(|(t, _)| (t[0] + t[1] + t[2]) / 3.0)
            .collect();
        let emits = [false, true, false, false, false];
        let surfaces = Surfaces {
            material: &material,
            emits: &emits,
        };
        let d = default_camera(&bvh, &bounds, &lights, false, &surfaces);
        let dir = Vec3::from(d.desc.target) - Vec3::from(d.desc.origin);
        assert!(dir.z < -0.9, "looks along {dir}: {}", d.how);
        assert!(d.how.contains("-z") && d.how.contains("+x"), "{}", d.how);
        assert!(d.warning.unwrap().contains("the view that sees the most"));
    }
}
