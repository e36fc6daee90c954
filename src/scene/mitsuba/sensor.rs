//! The sensor (camera, film, sampler) and the integrator: what the file asks of a render.

use super::*;

impl<'a> Loader<'a> {
    pub(super) fn sensor(&mut self, el: &'a El) -> R<()> {
        let kind = el.kind();
        if !known_plugin("sensor", kind) {
            return Err(format!("{}: unknown sensor plugin '{kind}'", el.at));
        }
        if self.sensor_seen {
            self.mark_all(el);
            self.warn(
                "second sensor",
                format!("{}: more than one sensor: kalos uses the first", el.at),
            );
            return Ok(());
        }
        self.sensor_seen = true;
        // film and sampler first: the field of view may depend on the aspect ratio
        let (mut w, mut h) = (768u32, 576u32);
        // an hdrfilm without <rfilter> reconstructs with Mitsuba's default Gaussian
        let mut filter = PixelFilter::MITSUBA_DEFAULT;
        for c in &el.children {
            let t = if c.tag == "ref" { self.resolve(c)? } else { c };
            match t.tag.as_str() {
                "film" => {
                    c.used.set(true);
                    if !known_plugin("film", t.kind()) {
                        return Err(format!("{}: unknown film plugin '{}'", t.at, t.kind()));
                    }
                    if let Some(x) = self.int(t, "width")? {
                        w = u32::try_from(x).map_err(|_| format!("{}: film width {x}", t.at))?;
                    }
                    if let Some(x) = self.int(t, "height")? {
                        h = u32::try_from(x).map_err(|_| format!("{}: film height {x}", t.at))?;
                    }
                    crate::film::check_resolution(w, h)
                        .map_err(|e| format!("{}: film: {e}", t.at))?;
                    for r in t.children.iter().filter(|r| r.tag == "rfilter") {
                        r.used.set(true);
                        filter = self.rfilter(r)?;
                    }
                    for k in [
                        "crop_offset_x",
                        "crop_offset_y",
                        "crop_width",
                        "crop_height",
                    ] {
                        if self.prop(t, k).is_some() {
                            self.warn(
                                "crop",
                                format!("{}: film cropping is not supported: the whole image is rendered", t.at),
                            );
                        }
                    }
                    self.unused(t, &format!("film '{}'", t.kind()));
                }
                "sampler" => {
                    c.used.set(true);
                    if !known_plugin("sampler", t.kind()) {
                        return Err(format!("{}: unknown sampler plugin '{}'", t.at, t.kind()));
                    }
                    if let Some(n) = self.int(t, "sample_count")? {
                        let n = u32::try_from(n).ok().filter(|n| *n >= 1).ok_or_else(|| {
                            format!("{}: sample_count {n}: must be at least 1", t.at)
                        })?;
                        self.desc.defaults.spp = Some(n);
                    }
                    self.mark_all(t);
                }
                _ => {}
            }
        }
        self.desc.defaults.res = Some((w, h));
        if kind == "orthographic" {
            return self.orthographic(el, filter);
        }
        if !matches!(kind, "perspective" | "thinlens") {
            self.mark_all(el);
            self.warn(
                &format!("sensor {kind}"),
                format!(
                    "{}: unsupported sensor '{kind}': kalos uses its default camera",
                    el.at
                ),
            );
            return Ok(());
        }
        if kind == "thinlens" {
            self.warn(
                "thinlens",
                format!(
                    "{}: thinlens sensor rendered as a pinhole (no depth of field)",
                    el.at
                ),
            );
            for k in ["aperture_radius", "focus_distance"] {
                self.prop(el, k);
            }
        }
        let (fov, fov_axis) = self.fov(el, w, h)?;
        let xf = self.transform(el, "to_world")?;
        let origin = xf.transform_point3(Vec3::ZERO);
        let fwd = xf.transform_vector3(Vec3::Z).normalize_or_zero();
        let up = xf.transform_vector3(Vec3::Y).normalize_or_zero();
        if Mat3::from_mat4(xf).determinant() < 0.0 {
            self.warn(
                "mirrored sensor",
                format!(
                    "{}: the sensor's to_world mirrors the image (negative determinant): kalos renders it unmirrored",
                    el.at
                ),
            );
        }
        let cam = CameraDesc {
            origin: origin.into(),
            target: (origin + fwd).into(),
            up: up.into(),
            fov,
            fov_axis,
            projection: Projection::Perspective,
            filter,
        };
        cam.validate()
            .map_err(|e| format!("{}: sensor: {e}", el.at))?;
        self.desc.camera = Some(cam);
        self.unused(el, &format!("sensor '{kind}'"));
        Ok(())
    }

    /// A perspective field of view, as Mitsuba's `parse_fov` reads it: `fov` along
    /// `fov_axis` (x by default), else `focal_length` (50mm by default) over a `w` x `h`
    /// image's horizontal extent.
    pub(super) fn fov(&mut self, el: &'a El, w: u32, h: u32) -> R<(f32, FovAxis)> {
        let axis = self.string(el, "fov_axis")?.unwrap_or_else(|| "x".into());
        let (fov, axis) = match (self.float(el, "fov")?, self.string(el, "focal_length")?) {
            (Some(f), _) => (f, axis),
            (None, fl) => {
                let fl = fl.unwrap_or_else(|| "50mm".into());
                let mm: f32 = fl
                    .trim()
                    .trim_end_matches("mm")
                    .trim()
                    .parse()
                    .ok()
                    .filter(|v: &f32| *v > 0.0 && v.is_finite())
                    .ok_or_else(|| {
                        format!("{}: focal_length \"{fl}\": expected e.g. 50mm", el.at)
                    })?;
                // Mitsuba's parse_fov: a 35 mm film's diagonal (36 x 24 mm) spread over
                // this film's aspect ratio gives the horizontal extent (fov_axis is not read)
                let aspect = w as f32 / h as f32;
                let half_x = 18.0f32.hypot(12.0) / (1.0 + 1.0 / (aspect * aspect)).sqrt();
                ((2.0 * (half_x / mm).atan()).to_degrees(), "x".to_string())
            }
        };
        if !(fov > 0.0 && fov < 180.0) {
            return Err(format!("{}: fov {fov}: must be in (0, 180) degrees", el.at));
        }
        let fov_axis = FovAxis::parse(&axis).ok_or_else(|| {
            format!(
                "{}: fov_axis \"{axis}\": expected x, y, diagonal, smaller or larger",
                el.at
            )
        })?;
        Ok((fov, fov_axis))
    }

    /// An `<rfilter>`: box, tent (`radius`, 1 pixel) and Gaussian (`stddev`, 0.5 pixels)
    /// as Mitsuba defines them; the negative-lobed filters are warned and rendered as a box.
    fn rfilter(&mut self, r: &'a El) -> R<PixelFilter> {
        let kind = r.kind();
        if !known_plugin("rfilter", kind) {
            return Err(format!("{}: unknown rfilter plugin '{kind}'", r.at));
        }
        let f = match kind {
            "box" => PixelFilter::Box,
            "tent" => PixelFilter::Tent {
                radius: self.float(r, "radius")?.unwrap_or(1.0),
            },
            "gaussian" => PixelFilter::Gaussian {
                stddev: self.float(r, "stddev")?.unwrap_or(0.5),
            },
            _ => {
                self.mark_all(r);
                self.warn(
                    "rfilter",
                    format!(
                        "{}: pixel filter '{kind}' has negative lobes: kalos uses a box filter (the same mean, sharper edges, more noise)",
                        r.at
                    ),
                );
                return Ok(PixelFilter::Box);
            }
        };
        f.validate()
            .map_err(|e| format!("{}: rfilter: {e}", r.at))?;
        self.unused(r, &format!("rfilter '{kind}'"));
        Ok(f)
    }

    /// Mitsuba's `orthographic` sensor: parallel rays along +z of `to_world` from its
    /// near clip plane, over [-1, 1] x [-1/aspect, 1/aspect] of its local x and y.
    fn orthographic(&mut self, el: &'a El, filter: PixelFilter) -> R<()> {
        let near = self.float(el, "near_clip")?.unwrap_or(1e-2);
        let far = self.float(el, "far_clip")?.unwrap_or(1e4);
        if !(near >= 0.0 && far > near && far.is_finite()) {
            return Err(format!(
                "{}: near_clip {near} and far_clip {far}: need 0 <= near_clip < far_clip",
                el.at
            ));
        }
        let xf = self.transform(el, "to_world")?;
        let (sx, sy) = (
            xf.transform_vector3(Vec3::X).length(),
            xf.transform_vector3(Vec3::Y).length(),
        );
        if !(sx > 0.0 && sy > 0.0 && sx.is_finite() && sy.is_finite()) {
            return Err(format!(
                "{}: orthographic sensor: its to_world collapses the film (x scale {sx}, y scale {sy})",
                el.at
            ));
        }
        let origin = xf.transform_point3(Vec3::new(0.0, 0.0, near));
        let fwd = xf.transform_vector3(Vec3::Z).normalize_or_zero();
        let cam = CameraDesc {
            origin: origin.into(),
            target: (origin + fwd).into(),
            up: xf.transform_vector3(Vec3::Y).normalize_or_zero().into(),
            fov: 90.0,
            fov_axis: FovAxis::X,
            projection: Projection::Orthographic {
                scale_x: sx,
                scale_y: sy,
            },
            filter,
        };
        cam.validate()
            .map_err(|e| format!("{}: sensor: {e}", el.at))?;
        self.desc.camera = Some(cam);
        self.unused(el, "sensor 'orthographic'");
        Ok(())
    }

    pub(super) fn integrator(&mut self, el: &'a El) -> R<()> {
        let kind = el.kind();
        if !known_plugin("integrator", kind) {
            return Err(format!("{}: unknown integrator plugin '{kind}'", el.at));
        }
        use crate::options::IntegratorKind;
        match kind {
            "path" | "volpath" | "volpathmis" | "prb" | "prbvolpath" | "bdpt" | "ptracer" => {
                // the file's estimator, or kalos' nearest: the path tracer (the same
                // image) for Mitsuba's particle tracer (kalos' BDPT, whose light tracing is
                // the particle tracer's, takes area lights only) and for the volumetric
                // and differentiable path tracers
                let (kalos, said) = match kind {
                    "path" => (IntegratorKind::Path, None),
                    "bdpt" => (IntegratorKind::Bdpt, None),
                    "ptracer" => (
                        IntegratorKind::Path,
                        Some("rendered with kalos' path tracer (the same image; its BDPT, whose light tracing is the particle tracer's, takes area lights only)"),
                    ),
                    _ => (
                        IntegratorKind::Path,
                        Some("rendered with kalos' path tracer (the same image without media)"),
                    ),
                };
                if let Some(said) = said {
                    self.warn(
                        "integrator",
                        format!("{}: integrator '{kind}': {said} (see --integrator)", el.at),
                    );
                }
                self.desc.defaults.integrator = Some(kalos);
                if let Some(d) = self.int(el, "max_depth")? {
                    if d < -1 || d == 0 {
                        return Err(format!(
                            "{}: max_depth {d}: must be -1 (unlimited) or at least 1",
                            el.at
                        ));
                    }
                    self.desc.defaults.max_depth = Some(d.min(i32::MAX as i64) as i32);
                }
                // Mitsuba's roulette starts at depth rr_depth (default 5), counting the
                // first hit as 1; kalos' --rr-min-depth counts the reflections before it.
                let rr_depth = self.int(el, "rr_depth")?.unwrap_or(5);
                self.desc.defaults.rr_min_depth =
                    Some(rr_depth.saturating_sub(1).clamp(0, u32::MAX as i64) as u32);
                if self.boolean(el, "hide_emitters")? == Some(true) {
                    self.warn(
                        "hide_emitters",
                        format!(
                            "{}: hide_emitters is not supported: emitters are visible",
                            el.at
                        ),
                    );
                }
                self.unused(el, &format!("integrator '{kind}'"));
            }
            // direct light (emitter and BSDF sampling with MIS) is the path tracer's
            // max_depth 2: the same estimator
            "direct" => {
                self.mark_all(el);
                self.desc.defaults.max_depth = Some(2);
                self.desc.defaults.integrator = Some(IntegratorKind::Path);
            }
            // Mitsuba's AOV and moment integrators: the radiance is their nested
            // integrator's (moment adds the second moment, which kalos' film keeps anyway)
            "aov" | "moment" => {
                self.mark_all(el);
                if kind == "aov" {
                    self.warn(
                        "integrator aov",
                        format!(
                            "{}: integrator 'aov': kalos renders the radiance of the nested integrator, without the AOVs (see --aovs)",
                            el.at
                        ),
                    );
                }
                for c in el.children.iter().filter(|c| c.tag == "integrator") {
                    self.integrator(c)?;
                }
            }
            k => {
                self.mark_all(el);
                self.warn(
                    "integrator",
                    format!("{}: integrator '{k}' is not in kalos: rendered with its path tracer (see --integrator)", el.at),
                );
            }
        }
        Ok(())
    }
}
