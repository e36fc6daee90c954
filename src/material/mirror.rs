//! Ideal mirror (MTL illum 5): a Dirac delta lobe with reflectance ks.

use super::BsdfSample;
use crate::spectrum::Spectrum;
use glam::Vec3;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mirror {
    pub ks: [f32; 3],
}

impl Mirror {
    #[inline]
    pub fn sample<const N: usize>(&self, wo: Vec3) -> Option<BsdfSample<N>> {
        if wo.z <= 0.0 {
            return None;
        }
        Some(BsdfSample {
            wi: Vec3::new(-wo.x, -wo.y, wo.z),
            weight: Spectrum::from_rgb(self.ks),
            pdf: 1.0,
            delta: true,
        })
    }
}
