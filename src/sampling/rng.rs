//! Random numbers as a pure function of (seed, stream, pixel, sample index, dimension).
//!
//! The image therefore does not depend on threads or scheduling. With `dependent` set
//! the pixel is left out of the function: every pixel then uses the same random numbers
//! for the same sample index, which is exactly the "dependent tests" of Csonka et al.
//! `stream` separates phases (the independent phase of DTF uses another stream).

/// Which low-level generator.
#[derive(
    Clone,
    Copy,
    Debug,
    Default,
    PartialEq,
    Eq,
    serde::Serialize,
    serde::Deserialize,
    clap::ValueEnum,
)]
#[serde(rename_all = "lowercase")]
pub enum SamplerKind {
    /// A hash of the coordinates: independent uniform numbers.
    #[value(alias = "independent")]
    Random,
    /// Owen-scrambled Sobol (Burley 2020), scrambled per pixel: the default, for its lower
    /// error at equal time (path tracing with the same roulette at 10 s, 2026-12-06, Xeon
    /// with AVX-512: 0.47-0.60x the independent sampler's RMSE on the Cornell box,
    /// 0.27-0.38x on a furnished room; `docs/results/auto.md`).
    #[default]
    Sobol,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SamplerConfig {
    pub kind: SamplerKind,
    pub seed: u64,
    /// Leave the pixel out of the random function (dependent tests).
    pub dependent: bool,
}

impl Default for SamplerConfig {
    fn default() -> Self {
        // (the independent sampler: the library's known-answer tests take their standard
        // errors from independent samples; renders get `SamplerKind::default()` from
        // `RenderJob`'s option)
        SamplerConfig {
            kind: SamplerKind::Random,
            seed: 0,
            dependent: false,
        }
    }
}

#[inline]
pub fn mix64(mut z: u64) -> u64 {
    // splitmix64 finaliser
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

#[inline]
fn to_unit(x: u32) -> f32 {
    // 24 high bits -> [0, 1)
    (x >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// Dimensions past this use the hash even in Sobol mode.
const SOBOL_DIMS: u32 = sobol_burley::NUM_DIMENSIONS;

/// The random numbers of one sample of one pixel.
#[derive(Clone, Copy, Debug)]
pub struct SampleStream {
    kind: SamplerKind,
    key: u64,
    /// mix64(key, index): the per-sample base of the hash (random mode).
    base: u64,
    index: u64,
    dim: u32,
    /// Sobol: the last set of four dimensions computed (`sobol_burley::sample_4d`, four
    /// dimensions for about the price of one) and its values; u32::MAX for none.
    set4: u32,
    cache4: [f32; 4],
}

impl SampleStream {
    /// Stream for `sample_index` of `pixel` (ignored when dependent) in `stream`.
    #[inline]
    pub fn new(cfg: &SamplerConfig, stream: u32, pixel: u32, sample_index: u64) -> Self {
        let mut key = mix64(cfg.seed ^ 0x6b61_6c6f_7300_0000);
        key = mix64(key ^ (stream as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15));
        if !cfg.dependent {
            key = mix64(key ^ ((pixel as u64) << 1 | 1));
        }
        SampleStream {
            kind: cfg.kind,
            key,
            base: mix64(key ^ sample_index.wrapping_mul(0xd1b5_4a32_d192_ed03)),
            index: sample_index,
            dim: 0,
            set4: u32::MAX,
            cache4: [0.0; 4],
        }
    }

    /// A stream of the same sample index made independent of this one by `salt` (e.g. a
    /// pixel, so that one part of a dependent sample is drawn per pixel after all).
    #[inline]
    pub fn decorrelated(&self, salt: u64) -> SampleStream {
        let key = mix64(self.key ^ mix64(salt ^ 0x5a17_ed00_0000_0001));
        SampleStream {
            kind: self.kind,
            key,
            base: mix64(key ^ self.index.wrapping_mul(0xd1b5_4a32_d192_ed03)),
            index: self.index,
            dim: 0,
            set4: u32::MAX,
            cache4: [0.0; 4],
        }
    }

    /// Jump to a fixed dimension (so that each bounce uses the same dimensions).
    #[inline]
    pub fn set_dimension(&mut self, dim: u32) {
        self.dim = dim;
    }

    #[inline]
    pub fn dimension(&self) -> u32 {
        self.dim
    }

    #[inline]
    pub fn next_1d(&mut self) -> f32 {
        let d = self.dim;
        self.dim += 1;
        match self.kind {
            SamplerKind::Sobol if d < SOBOL_DIMS && self.index < (1 << 16) => {
                // the same numbers as sobol_burley::sample(index, d, seed), four at a time
                let set = d / 4;
                if self.set4 != set {
                    self.cache4 = sobol_burley::sample_4d(self.index as u32, set, self.key as u32);
                    self.set4 = set;
                }
                self.cache4[(d % 4) as usize].min(ONE_MINUS_EPS)
            }
            _ => {
                // one finaliser per number: the base already mixes seed, stream, pixel, index
                let h = mix64(
                    self.base
                        .wrapping_add((d as u64 + 1).wrapping_mul(0x9e37_79b9_7f4a_7c15)),
                );
                to_unit((h >> 32) as u32)
            }
        }
    }

    // (always: since 2026-12-06's merges the compiler had left it out of line, a call
    // per vertex and two per light sample in the path tracer)
    #[inline(always)]
    pub fn next_2d(&mut self) -> glam::Vec2 {
        let a = self.next_1d();
        let b = self.next_1d();
        glam::Vec2::new(a, b)
    }
}

pub const ONE_MINUS_EPS: f32 = 1.0 - f32::EPSILON / 2.0;

/// A small sequential generator (PCG32) for tests, benchmarks and tools. Never for
/// rendering: a render's numbers are pure functions of their coordinates (`SampleStream`).
#[derive(Clone, Debug)]
pub struct SeqRng(u64);

impl SeqRng {
    /// The seed is the generator's initial state.
    pub fn new(seed: u64) -> Self {
        SeqRng(seed)
    }
    pub fn next_u32(&mut self) -> u32 {
        let old = self.0;
        self.0 = old
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let x = (((old >> 18) ^ old) >> 27) as u32;
        x.rotate_right((old >> 59) as u32)
    }
    /// Uniform in [0, 1), 24 bits.
    pub fn next_f32(&mut self) -> f32 {
        to_unit(self.next_u32())
    }
    pub fn next_2d(&mut self) -> glam::Vec2 {
        let a = self.next_f32();
        glam::Vec2::new(a, self.next_f32())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pure_function_of_coordinates() {
        let cfg = SamplerConfig::default();
        let mut a = SampleStream::new(&cfg, 0, 17, 5);
        let mut b = SampleStream::new(&cfg, 0, 17, 5);
        for _ in 0..10 {
            assert_eq!(a.next_1d(), b.next_1d());
        }
    }

    #[test]
    fn sobol_four_at_a_time_is_sobol_one_at_a_time() {
        let cfg = SamplerConfig {
            kind: SamplerKind::Sobol,
            seed: 9,
            dependent: false,
        };
        for index in [0, 1, 7, 1000, 65535] {
            let mut s = SampleStream::new(&cfg, 2, 31, index);
            // forwards, with jumps backwards and into the middle of a set
            for d in (0..40).chain([3, 2, 17, 16, 5, 63, 62]) {
                s.set_dimension(d);
                let want = sobol_burley::sample(index as u32, d, s.key as u32).min(ONE_MINUS_EPS);
                assert_eq!(s.next_1d(), want, "index {index} dimension {d}");
            }
        }
    }

    #[test]
    fn dependent_streams_ignore_the_pixel() {
        for kind in [SamplerKind::Random, SamplerKind::Sobol] {
            let dep = SamplerConfig {
                kind,
                seed: 3,
                dependent: true,
            };
            let ind = SamplerConfig {
                dependent: false,
                ..dep
            };
            let mut a = SampleStream::new(&dep, 0, 1, 9);
            let mut b = SampleStream::new(&dep, 0, 1000, 9);
            let mut c = SampleStream::new(&ind, 0, 1, 9);
            let mut d = SampleStream::new(&ind, 0, 1000, 9);
            let (x, y, z, w) = (a.next_1d(), b.next_1d(), c.next_1d(), d.next_1d());
            assert_eq!(x, y);
            assert_ne!(z, w);
            // streams (phases) are independent of each other
            let mut e = SampleStream::new(&dep, 1, 1, 9);
            assert_ne!(x, e.next_1d());
        }
    }

    #[test]
    fn uniform_mean_and_range() {
        for kind in [SamplerKind::Random, SamplerKind::Sobol] {
            let cfg = SamplerConfig {
                kind,
                seed: 1,
                dependent: false,
            };
            let mut sum = 0.0f64;
            let n = 4096;
            for i in 0..n {
                let mut s = SampleStream::new(&cfg, 0, 7, i);
                s.set_dimension(3);
                let u = s.next_1d();
                assert!((0.0..1.0).contains(&u));
                sum += u as f64;
            }
            assert!((sum / n as f64 - 0.5).abs() < 0.01, "{kind:?}");
        }
    }
}
