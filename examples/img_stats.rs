//! Diagnostic: luminance sums of image B over the pixels where image A is zero / nonzero,
//! against a reference R. `cargo run --example img_stats -- MASK.exr IMG.exr REF.exr`
fn main() {
    let a: Vec<String> = std::env::args().collect();
    let rd = |f: &str| kalos::image_io::read_image(std::path::Path::new(f)).unwrap();
    let (m, img, r) = (rd(&a[1]), rd(&a[2]), rd(&a[3]));
    let lum = |c: [f32; 3]| 0.2126 * c[0] as f64 + 0.7152 * c[1] as f64 + 0.0722 * c[2] as f64;
    let mut s = [[0.0f64; 2]; 2];
    let mut n = [0usize; 2];
    for i in 0..m.data.len() {
        let k = (m.data[i][0] > 0.0) as usize;
        n[k] += 1;
        s[k][0] += lum(img.data[i]);
        s[k][1] += lum(r.data[i]);
    }
    for k in 0..2 {
        println!(
            "mask {}: {} pixels, image/reference {:.5} (image {:.3}, reference {:.3})",
            if k == 1 { "nonzero" } else { "zero" },
            n[k],
            s[k][0] / s[k][1],
            s[k][0],
            s[k][1]
        );
    }
}
