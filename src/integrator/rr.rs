//! Every Russian-roulette rule of kalos lives here; every estimator calls it.
//!
//! `Classic`: continue with probability s = the luminance of the local albedo (clamped to
//! [0, 1]), as the roulette paper describes the usual practice; a terminated walk
//! contributes zero and a continued one is divided by s.

use crate::spectrum::Spectrum;

#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum RrMode {
    Off,
    Classic,
}

impl RrMode {
    pub fn parse(s: &str) -> Option<RrMode> {
        match s {
            "off" => Some(RrMode::Off),
            "classic" => Some(RrMode::Classic),
            _ => None,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Roulette {
    pub mode: RrMode,
    /// Bounces (reflections) before roulette starts; 0 = at every reflection.
    pub min_depth: u32,
}

impl Default for Roulette {
    fn default() -> Self {
        Roulette {
            mode: RrMode::Classic,
            min_depth: 0,
        }
    }
}

impl Roulette {
    /// Continuation probability s at reflection number `bounce` (0-based) of a surface with
    /// local albedo `albedo`. 1 means no roulette.
    #[inline]
    pub fn continuation<const N: usize>(&self, bounce: u32, albedo: &Spectrum<N>) -> f32 {
        if bounce < self.min_depth {
            return 1.0;
        }
        match self.mode {
            RrMode::Off => 1.0,
            RrMode::Classic => albedo.luminance().clamp(0.0, 1.0),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    #[test]
    fn classic_uses_albedo_luminance() {
        let r = Roulette::default();
        let a = Spectrum::<3>([0.5, 0.5, 0.5]);
        assert!((r.continuation(0, &a) - 0.5).abs() < 1e-6);
        assert_eq!(r.continuation(0, &Spectrum::<3>([2.0, 2.0, 2.0])), 1.0);
        let off = Roulette {
            mode: RrMode::Off,
            min_depth: 0,
        };
        assert_eq!(off.continuation(5, &a), 1.0);
        let late = Roulette {
            mode: RrMode::Classic,
            min_depth: 3,
        };
        assert_eq!(late.continuation(2, &a), 1.0);
    }
}
