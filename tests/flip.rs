//! FLIP against the reference implementation: NVIDIA's `flip-evaluator` 1.7 (PyPI) on the
//! image pairs in tests/data/flip (kalos's cornell at 48x40, 4 spp seed 1 against 64 spp
//! seed 2, written as PNG and as EXR). The reference values were made with
//!
//! ```python
//! import flip_evaluator as flip
//! flip.evaluate("reference.png", "test.png", "LDR")[1]  # 0.15554501116275787
//! flip.evaluate("reference.exr", "test.exr", "HDR")     # 0.36886686086654663, its
//! # parameters: startExposure -2.7839620113372803, stopExposure 5.538632392883301,
//! # numExposures 9; the map's pixel (x 0, y 0) 0.12707475, (x 20, y 20) 0.3805632
//! ```
//!
//! so this test needs no Python. kalos must agree within 1%.

use kalos::image_io::read_image;
use kalos::metrics::flip::{exposures, flip, Range};
use std::path::Path;

fn pair(ext: &str) -> (kalos::image_io::RgbImage, kalos::image_io::RgbImage) {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/flip");
    (
        read_image(&dir.join(format!("test.{ext}"))).unwrap(),
        read_image(&dir.join(format!("reference.{ext}"))).unwrap(),
    )
}

fn close(got: f64, want: f64, what: &str) {
    assert!(
        ((got - want) / want).abs() < 0.01,
        "{what}: kalos {got}, flip-evaluator {want}"
    );
}

#[test]
fn ldr_flip_matches_flip_evaluator_on_png() {
    let (t, r) = pair("png");
    let f = flip(&t, &r, Range::Ldr).unwrap();
    close(f.mean, 0.15554501116275787, "LDR-FLIP mean");
}

#[test]
fn hdr_flip_matches_flip_evaluator_on_exr() {
    let (t, r) = pair("exr");
    let (start, stop, n) = exposures(&r.data);
    close(start as f64, -2.7839620113372803, "start exposure");
    close(stop as f64, 5.538632392883301, "stop exposure");
    assert_eq!(n, 9);
    let f = flip(&t, &r, Range::Hdr).unwrap();
    close(f.mean, 0.36886686086654663, "HDR-FLIP mean");
    close(f.map[0] as f64, 0.12707475, "pixel (0, 0)");
    close(f.map[20 * 48 + 20] as f64, 0.3805632, "pixel (20, 20)");
}
