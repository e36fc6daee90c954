//! Mitsuba-agreement tests of what the reader gives shading: a conductor's constant eta
//! and k. (Numbers from Mitsuba 3.9.1, `bench/mitsuba-normalmap-values.py` and the
//! scalar_rgb conductor noted at each test.)

use super::tests::scene;
use super::*;

/// A conductor's `<spectrum name="eta" value="0.789"/>` is Mitsuba's uniform spectrum:
/// 0.789 in every channel (read as an emission it would be an equal-energy white, a
/// 1.3% redder reflection). Mitsuba 3.9.1 (scalar_rgb) reflects 0.923068 of the light at
/// normal incidence from eta 0.789, k 6.15, in each channel.
#[test]
fn a_conductors_constant_eta_and_k_are_grey() {
    let d = scene(
        r#"<shape type="cube"><bsdf type="conductor">
        <spectrum name="eta" value="0.789"/><spectrum name="k" value="6.15"/></bsdf></shape>"#,
    )
    .unwrap();
    let Some(SurfaceModel::Conductor { eta, k, .. }) = d.materials.last().unwrap().model else {
        panic!("not a conductor");
    };
    assert_eq!((eta, k), ([0.789; 3], [6.15; 3]));
    for i in 0..3 {
        let r = crate::material::conductor::fresnel_conductor(1.0, eta[i], k[i]);
        assert!((r - 0.923068).abs() < 1e-5, "channel {i}: {r}");
    }
}
