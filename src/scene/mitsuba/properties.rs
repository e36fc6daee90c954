//! Typed properties of an element: numbers, booleans, strings, points, transforms,
//! references, and the record of which parameters were read.

use super::*;

// ----------------------------------------------------------------------------------------
// Values
// ----------------------------------------------------------------------------------------

/// How deep BSDFs and textures may nest, references followed.
const MAX_BUILD_DEPTH: usize = 64;

/// Numbers in an attribute: separated by commas and/or white space.
pub(super) fn numbers(s: &str) -> Option<Vec<f32>> {
    s.split(|c: char| c == ',' || c.is_whitespace())
        .filter(|t| !t.is_empty())
        .map(|t| t.parse::<f32>().ok().filter(|v| v.is_finite()))
        .collect()
}

impl<'a> Loader<'a> {
    pub(super) fn resolve(&self, el: &'a El) -> R<&'a El> {
        if el.tag != "ref" {
            return Ok(el);
        }
        let id = el
            .attr("id")
            .ok_or_else(|| format!("{}: <ref> without an id", el.at))?;
        self.ids
            .get(id)
            .copied()
            .ok_or_else(|| format!("{}: <ref id=\"{id}\">: no element has that id", el.at))
    }

    /// `build(target)` for the element `el` names (itself, or what its `<ref>` resolves
    /// to), refusing a reference cycle and nesting deeper than `MAX_BUILD_DEPTH` (both
    /// would otherwise recurse without end).
    pub(super) fn building<T>(&self, el: &El, target: &El, build: impl FnOnce() -> R<T>) -> R<T> {
        let key = target as *const El;
        let depth = {
            let mut b = self.building.borrow_mut();
            if b.contains(&key) {
                let id = target.attr("id").unwrap_or("");
                return Err(format!(
                    "{}: <ref id=\"{id}\">: a cycle: the <{}> at {} contains a reference to itself",
                    el.at, target.tag, target.at
                ));
            }
            b.push(key);
            b.len()
        };
        let r = if depth > MAX_BUILD_DEPTH {
            Err(format!(
                "{}: <{}>: bsdfs and textures nested (through references) more than {MAX_BUILD_DEPTH} deep",
                el.at, target.tag
            ))
        } else {
            build()
        };
        self.building.borrow_mut().pop();
        r
    }

    /// The property child named `name` (marked as read).
    pub(super) fn prop(&self, el: &'a El, name: &str) -> Option<&'a El> {
        let c = el.children.iter().find(|c| c.name() == Some(name))?;
        c.used.set(true);
        Some(c)
    }

    pub(super) fn value<'b>(&self, p: &'b El) -> R<&'b str> {
        p.attr("value").ok_or_else(|| {
            format!(
                "{}: <{} name=\"{}\"> has no value attribute",
                p.at,
                p.tag,
                p.name().unwrap_or("")
            )
        })
    }

    pub(super) fn float(&self, el: &'a El, name: &str) -> R<Option<f32>> {
        let Some(p) = self.prop(el, name) else {
            return Ok(None);
        };
        match p.tag.as_str() {
            "float" | "integer" => {}
            // a texture or spectrum where a number is expected: its mean
            "rgb" | "spectrum" | "texture" | "ref" | "srgb" => {
                let c = self.color_of(p, Use::Unbounded)?;
                let rgb = self.mean_rgb(c, &p.at)?;
                return Ok(Some((rgb[0] + rgb[1] + rgb[2]) / 3.0));
            }
            t => {
                return Err(format!(
                    "{}: <{t} name=\"{name}\">: expected a <float>",
                    p.at
                ))
            }
        }
        let v = self.value(p)?;
        let f: f32 = v.trim().parse().map_err(|_| {
            format!(
                "{}: <{} name=\"{name}\" value=\"{v}\">: not a number",
                p.at, p.tag
            )
        })?;
        if !f.is_finite() {
            return Err(format!(
                "{}: <{} name=\"{name}\" value=\"{v}\">: not a finite number",
                p.at, p.tag
            ));
        }
        Ok(Some(f))
    }

    pub(super) fn int(&self, el: &'a El, name: &str) -> R<Option<i64>> {
        let Some(p) = self.prop(el, name) else {
            return Ok(None);
        };
        let v = self.value(p)?;
        v.trim().parse::<i64>().map(Some).map_err(|_| {
            format!(
                "{}: <{} name=\"{name}\" value=\"{v}\">: not an integer",
                p.at, p.tag
            )
        })
    }

    pub(super) fn boolean(&self, el: &'a El, name: &str) -> R<Option<bool>> {
        let Some(p) = self.prop(el, name) else {
            return Ok(None);
        };
        let v = self.value(p)?;
        // Mitsuba lower-cases the value first (Python writes True and False)
        match v.trim().to_ascii_lowercase().as_str() {
            "true" | "1" => Ok(Some(true)),
            "false" | "0" => Ok(Some(false)),
            _ => Err(format!(
                "{}: <boolean name=\"{name}\" value=\"{v}\">: expected true or false",
                p.at
            )),
        }
    }

    pub(super) fn string(&self, el: &'a El, name: &str) -> R<Option<String>> {
        match self.prop(el, name) {
            Some(p) => Ok(Some(self.value(p)?.to_string())),
            None => Ok(None),
        }
    }

    pub(super) fn vec3_attr(&self, p: &El, what: &str) -> R<Vec3> {
        if let Some(v) = p.attr("value") {
            let n = numbers(v).filter(|n| n.len() == 3 || n.len() == 1);
            return match n.as_deref() {
                Some([x, y, z]) => Ok(Vec3::new(*x, *y, *z)),
                Some([s]) => Ok(Vec3::splat(*s)),
                _ => Err(format!(
                    "{}: <{}> {what}: value \"{v}\" is not 1 or 3 finite numbers",
                    p.at, p.tag
                )),
            };
        }
        let c = |k: &str, d: f32| -> R<f32> {
            match p.attr(k) {
                None => Ok(d),
                Some(s) => s
                    .trim()
                    .parse::<f32>()
                    .ok()
                    .filter(|v| v.is_finite())
                    .ok_or_else(|| {
                        format!(
                            "{}: <{}> {what}: {k}=\"{s}\" is not a finite number",
                            p.at, p.tag
                        )
                    }),
            }
        };
        let d = if p.tag == "scale" { 1.0 } else { 0.0 };
        Ok(Vec3::new(c("x", d)?, c("y", d)?, c("z", d)?))
    }

    pub(super) fn point(&self, el: &'a El, name: &str) -> R<Option<Vec3>> {
        match self.prop(el, name) {
            Some(p) => Ok(Some(self.vec3_attr(p, name)?)),
            None => Ok(None),
        }
    }

    /// `to_world` (or another transform property): identity if absent.
    pub(super) fn transform(&self, el: &'a El, name: &str) -> R<Mat4> {
        let Some(t) = self.prop(el, name) else {
            return Ok(Mat4::IDENTITY);
        };
        if t.tag != "transform" {
            return Err(format!(
                "{}: <{} name=\"{name}\">: expected a <transform>",
                t.at, t.tag
            ));
        }
        let mut m = Mat4::IDENTITY;
        for op in &t.children {
            let step = match op.tag.as_str() {
                "translate" => Mat4::from_translation(self.vec3_attr(op, "translate")?),
                "scale" => {
                    let s = self.vec3_attr(op, "scale")?;
                    Mat4::from_scale(s)
                }
                "rotate" => {
                    let axis = if op.attr("value").is_some() {
                        self.vec3_attr(op, "rotate")?
                    } else {
                        let c = |k: &str| op.attr(k).map(|s| s.trim().parse::<f32>());
                        let f = |k: &str| -> R<f32> {
                            match c(k) {
                                None => Ok(0.0),
                                Some(Ok(v)) if v.is_finite() => Ok(v),
                                _ => Err(format!("{}: <rotate> {k}: not a finite number", op.at)),
                            }
                        };
                        Vec3::new(f("x")?, f("y")?, f("z")?)
                    };
                    let angle = op
                        .attr("angle")
                        .ok_or_else(|| format!("{}: <rotate> needs an angle (degrees)", op.at))?;
                    let angle: f32 = angle
                        .trim()
                        .parse()
                        .ok()
                        .filter(|a: &f32| a.is_finite())
                        .ok_or_else(|| format!("{}: <rotate angle=\"{angle}\">: not a number", op.at))?;
                    if axis.length_squared() == 0.0 {
                        return Err(format!("{}: <rotate>: the axis is zero", op.at));
                    }
                    Mat4::from_axis_angle(axis.normalize(), angle.to_radians())
                }
                "matrix" => {
                    let v = op
                        .attr("value")
                        .ok_or_else(|| format!("{}: <matrix> needs a value", op.at))?;
                    match numbers(v) {
                        // an affine transform: a projective last row would be dropped by
                        // every point transform below, so it is refused, not ignored
                        Some(n) if n.len() == 16 && n[12..] != [0.0, 0.0, 0.0, 1.0] => {
                            return Err(format!(
                                "{}: <matrix>: the last row is ({}, {}, {}, {}): kalos reads affine transforms (0, 0, 0, 1), not projective ones",
                                op.at, n[12], n[13], n[14], n[15]
                            ))
                        }
                        Some(n) if n.len() == 16 => {
                            Mat4::from_cols_array(&n.try_into().unwrap()).transpose()
                        }
                        Some(n) if n.len() == 9 => Mat4::from_mat3(
                            Mat3::from_cols_array(&n.try_into().unwrap()).transpose(),
                        ),
                        _ => {
                            return Err(format!(
                                "{}: <matrix value=\"...\">: expected 16 (or 9) finite numbers, row by row",
                                op.at
                            ))
                        }
                    }
                }
                "lookat" => {
                    let get = |k: &str| -> R<Option<Vec3>> {
                        match op.attr(k) {
                            None => Ok(None),
                            Some(s) => match numbers(s).as_deref() {
                                Some([x, y, z]) => Ok(Some(Vec3::new(*x, *y, *z))),
                                _ => Err(format!(
                                    "{}: <lookat {k}=\"{s}\">: expected 3 finite numbers",
                                    op.at
                                )),
                            },
                        }
                    };
                    let o = get("origin")?
                        .ok_or_else(|| format!("{}: <lookat> needs an origin", op.at))?;
                    let t = get("target")?
                        .ok_or_else(|| format!("{}: <lookat> needs a target", op.at))?;
                    let dir = (t - o).normalize_or_zero();
                    if dir == Vec3::ZERO {
                        return Err(format!("{}: <lookat>: origin and target coincide", op.at));
                    }
                    // no (or a zero) up: Mitsuba's coordinate_system(dir).first, the first
                    // of Duff et al.'s pair, which glam's any_orthonormal_pair computes
                    let up = match get("up")? {
                        Some(u) if u != Vec3::ZERO => u,
                        _ => dir.any_orthonormal_pair().0,
                    };
                    let left = up.cross(dir).normalize_or_zero();
                    if left == Vec3::ZERO {
                        return Err(format!(
                            "{}: <lookat>: up is parallel to the view direction (or zero)",
                            op.at
                        ));
                    }
                    let new_up = dir.cross(left);
                    Mat4::from_cols(
                        left.extend(0.0),
                        new_up.extend(0.0),
                        dir.extend(0.0),
                        o.extend(1.0),
                    )
                }
                t => {
                    return Err(format!(
                        "{}: <{t}> inside <transform>: expected translate, rotate, scale, matrix or lookat",
                        op.at
                    ))
                }
            };
            m = step * m;
        }
        if !m.is_finite() || m.determinant() == 0.0 {
            return Err(format!(
                "{}: <transform name=\"{name}\"> is singular or not finite",
                t.at
            ));
        }
        Ok(m)
    }

    /// Resolve a relative file name of the scene.
    pub(super) fn path(&self, name: &str) -> PathBuf {
        resolve(&self.search, &self.dir, name)
    }

    pub(super) fn mark_all(&self, el: &El) {
        for c in &el.children {
            c.used.set(true);
        }
    }

    /// Warn (once per plugin and name) about parameters that were never read.
    pub(super) fn unused(&self, el: &El, plugin: &str) {
        const QUIET: &[&str] = &[
            "near_clip",
            "far_clip",
            "focus_distance",
            "pixel_format",
            "component_format",
            "file_format",
            "id",
            "sample_visible",
            "banner",
            "high_quality_edges",
            "specular_sampling_weight",
            "seed",
        ];
        for c in &el.children {
            if c.used.get() {
                continue;
            }
            let n = c.name().unwrap_or(c.tag.as_str());
            if QUIET.contains(&n) {
                continue;
            }
            self.warn(
                &format!("unused {plugin} {n}"),
                format!(
                    "{}: parameter '{n}' of {plugin} is not supported: ignored",
                    c.at
                ),
            );
        }
    }
}
