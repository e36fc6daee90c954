//! The one interface an estimator writes to (`Integrator::sample`): camera samples for
//! their own pixel, splats to any pixel, and the layers a pipeline asks for (a part of
//! each sample's value kept apart, the rays each pixel cost, BDPT's strategies). An
//! estimator sees only this trait, never a film; the film's own sink (`RowSink`) buffers a
//! row of a pass and `Film::add_row` adds it in a fixed order, so the image is the same
//! bits for any thread count.

use super::{Film, PixelStats, Rejections};
use crate::math::Vec2;

/// The part of each camera sample's value that a sink keeps as a layer of its own.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Layer {
    /// The value alone.
    #[default]
    None,
    /// The emission BDPT's camera subpath sees directly (its s = 0 strategies whose camera
    /// vertices before the emitter are all Dirac; no extra ray); 0 for other estimators.
    Direct,
    /// The light seen directly through mirrors and glass, f(ray) (`integrator::visible`):
    /// one more walk of the camera ray, for estimators that do not splat.
    Visible,
}

/// One strategy (s, t)'s share of a camera sample (BDPT; pbrt's visualizestrategies).
#[derive(Clone, Copy, Debug)]
pub struct StrategySample {
    pub s: u32,
    pub t: u32,
    /// Film position: the camera sample's for t >= 2, the splat's for t = 1.
    pub raster: Vec2,
    /// Linear RGB, MIS-weighted.
    pub weighted: [f32; 3],
    /// Linear RGB, without the MIS weight.
    pub unweighted: [f32; 3],
    /// Emission seen directly: s = 0 and every camera vertex between the pinhole and the
    /// emitter (y_1 .. y_{t-2}) scattered by a Dirac lobe (mirrors, smooth glass), so the
    /// contribution is a function of the camera ray's jitter and the glass's Fresnel
    /// choices only (DTF adds it back unfiltered, `DirectMode`).
    pub direct: bool,
}

/// Where an estimator's results go.
pub trait Sink {
    /// The part of each sample's value this sink keeps apart (asked once per call of the
    /// estimator).
    fn layer(&self) -> Layer {
        Layer::None
    }
    /// Whether the sink reads each sample's rays ([`Sink::rays`]); the estimator then takes
    /// its samples one at a time.
    fn counts_rays(&self) -> bool {
        false
    }
    /// Whether the sink reads BDPT's strategies ([`Sink::strategy`]).
    fn wants_strategies(&self) -> bool {
        false
    }
    /// One camera sample of pixel `pixel` (row-major) and sample index `index`: its value
    /// (linear RGB) and the [`Sink::layer`] part of it (0 without a layer).
    fn sample(&mut self, pixel: u32, index: u64, value: [f32; 3], part: [f32; 3]);
    /// A contribution to the pixel at raster position `p` (pixel (x, y) covers
    /// [x, x+1) x [y, y+1)) by the sample or light path of index `index`; positions
    /// outside the image are the sink's to drop.
    fn splat(&mut self, index: u64, p: Vec2, rgb: [f32; 3]);
    /// The rays traced by one sample of pixel `pixel`.
    fn rays(&mut self, _pixel: u32, _rays: u64) {}
    /// One strategy's share of a sample of pixel `pixel`.
    fn strategy(&mut self, _pixel: u32, _st: &StrategySample) {}
}

/// One buffered contribution: to pixel `pixel` by the sample of index `index` (its batch).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Splat {
    pub pixel: u32,
    pub index: u32,
    pub rgb: [f32; 3],
}

/// The pixel a raster position falls in, if inside a width x height image.
#[inline]
pub fn raster_pixel(p: Vec2, width: u32, height: u32) -> Option<u32> {
    if !(p.x >= 0.0 && p.y >= 0.0) {
        return None;
    }
    let (x, y) = (p.x as u32, p.y as u32);
    (x < width && y < height).then(|| y * width + x)
}

/// Splats only (light paths traced for light tracing alone): a buffer the pass adds to the
/// film in a fixed order (`Film::add_splats`).
#[derive(Clone, Debug, Default)]
pub struct Splats {
    pub width: u32,
    pub height: u32,
    pub splats: Vec<Splat>,
}

impl Splats {
    pub fn new(width: u32, height: u32) -> Self {
        Splats {
            width,
            height,
            splats: Vec::new(),
        }
    }
}

impl Sink for Splats {
    /// A light pass has no camera samples.
    fn sample(&mut self, _pixel: u32, _index: u64, _value: [f32; 3], _part: [f32; 3]) {
        debug_assert!(false, "a splat buffer takes no camera samples");
    }
    #[inline]
    fn splat(&mut self, index: u64, p: Vec2, rgb: [f32; 3]) {
        if let Some(pixel) = raster_pixel(p, self.width, self.height) {
            self.splats.push(Splat {
                pixel,
                // (a splat's batch: the index's low bits are enough)
                index: index as u32,
                rgb,
            });
        }
    }
}

/// What a row of a pass leaves to be added to the film after the pass.
#[derive(Default)]
pub struct RowOut {
    pub rejected: Rejections,
    /// For a splatting film: the row's camera samples (pixel, index, value), added with
    /// their batches after the pass.
    samples: Vec<Splat>,
    /// With the direct layer: the same samples less their light seen directly.
    rest: Vec<Splat>,
    splats: Splats,
}

/// The film's sink for one row of a pass: samples of a film without splats go straight
/// into the row's pixels (checked finite); a splatting film's samples and every splat are
/// buffered in [`RowOut`]. With [`Layer::Visible`] the value less the light seen directly
/// goes to the row's pixels and the light seen directly to `visible`'s (a sample rejected
/// in either part is left out of both); with [`Layer::Direct`] the sample and the sample
/// less its emission seen directly are buffered for two films (`Film::add_row`).
pub struct RowSink<'a> {
    /// The row's first pixel.
    start: u32,
    pixels: &'a mut [PixelStats],
    visible: Option<&'a mut [PixelStats]>,
    rays: Option<&'a mut [u64]>,
    layer: Layer,
    splatting: bool,
    pub out: RowOut,
}

impl<'a> RowSink<'a> {
    /// The sink of row `y` of `film`-sized passes, writing `pixels` (the row's); with
    /// `visible` the [`Layer::Visible`] row, with `rays` each pixel's rays; `direct` asks for
    /// [`Layer::Direct`]; `splatting` when the film keeps splats.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        width: u32,
        height: u32,
        y: u32,
        pixels: &'a mut [PixelStats],
        visible: Option<&'a mut [PixelStats]>,
        rays: Option<&'a mut [u64]>,
        direct: bool,
        splatting: bool,
    ) -> Self {
        let layer = match (&visible, direct) {
            (Some(_), _) => Layer::Visible,
            (None, true) => Layer::Direct,
            (None, false) => Layer::None,
        };
        RowSink {
            start: y * width,
            pixels,
            visible,
            rays,
            layer,
            splatting,
            out: RowOut {
                splats: Splats::new(width, height),
                ..Default::default()
            },
        }
    }
}

#[inline]
fn minus(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

impl Sink for RowSink<'_> {
    fn layer(&self) -> Layer {
        self.layer
    }
    fn counts_rays(&self) -> bool {
        self.rays.is_some()
    }
    #[inline]
    fn sample(&mut self, pixel: u32, index: u64, value: [f32; 3], part: [f32; 3]) {
        let x = (pixel - self.start) as usize;
        // (a sample's batch: the index's low bits are enough)
        let batch = index as u32;
        match self.layer {
            Layer::Visible => {
                let v = minus(value, part);
                let mut r = Rejections::default();
                if r.check(&v) && r.check(&part) {
                    self.pixels[x].push(v);
                    if let Some(vr) = self.visible.as_deref_mut() {
                        vr[x].push(part);
                    }
                }
                self.out.rejected.add(&r);
            }
            Layer::Direct => {
                self.out.samples.push(Splat {
                    pixel,
                    index: batch,
                    rgb: value,
                });
                self.out.rest.push(Splat {
                    pixel,
                    index: batch,
                    rgb: minus(value, part),
                });
            }
            Layer::None if self.splatting => self.out.samples.push(Splat {
                pixel,
                index: batch,
                rgb: value,
            }),
            Layer::None => {
                if self.out.rejected.check(&value) {
                    self.pixels[x].push(value);
                }
            }
        }
    }
    #[inline]
    fn splat(&mut self, index: u64, p: Vec2, rgb: [f32; 3]) {
        self.out.splats.splat(index, p, rgb);
    }
    #[inline]
    fn rays(&mut self, pixel: u32, rays: u64) {
        if let Some(r) = self.rays.as_deref_mut() {
            r[(pixel - self.start) as usize] += rays;
        }
    }
}

impl Film {
    /// Adds what a row of a pass buffered: its rejections, its camera samples (each also
    /// counted as a light path of its batch when the film splats) and its splats. With
    /// `rest` (the [`Layer::Direct`] film) each sample goes to both films or, if either
    /// value is not finite, to neither (this film counts the rejection).
    pub fn add_row(&mut self, o: &RowOut, mut rest: Option<&mut Film>) {
        self.rejected.add(&o.rejected);
        for (k, sm) in o.samples.iter().enumerate() {
            if let Some(r) = rest.as_deref_mut() {
                let rv = &o.rest[k];
                let mut j = Rejections::default();
                if j.check(&sm.rgb) && j.check(&rv.rgb) {
                    self.add_sample(sm.pixel as usize, sm.index, sm.rgb);
                    r.add_sample(rv.pixel as usize, rv.index, rv.rgb);
                } else {
                    self.rejected.add(&j);
                }
            } else {
                self.add_sample(sm.pixel as usize, sm.index, sm.rgb);
            }
            if let Some(sf) = self.splats.as_mut() {
                sf.add_light_path(sm.index);
            }
        }
        self.add_splats(&o.splats.splats);
    }

    /// Adds splats to the film's splat image; non-finite ones are rejected and counted.
    pub fn add_splats(&mut self, splats: &[Splat]) {
        for sp in splats {
            let mut r = Rejections::default();
            if r.check(&sp.rgb) {
                if let Some(sf) = self.splats.as_mut() {
                    sf.add_splat(sp.pixel as usize, sp.index, sp.rgb);
                }
            } else {
                self.rejected.add(&r);
            }
        }
    }
}
