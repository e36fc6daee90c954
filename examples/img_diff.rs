//! Largest per-pixel difference between two images, absolute and relative:
//! `cargo run --release --example img_diff -- a.exr b.exr`.
fn main() {
    let a: Vec<String> = std::env::args().collect();
    if a.len() != 3 {
        eprintln!("usage: img_diff A B");
        std::process::exit(2);
    }
    let x = kalos::image_io::read_image(std::path::Path::new(&a[1])).unwrap();
    let y = kalos::image_io::read_image(std::path::Path::new(&a[2])).unwrap();
    assert_eq!((x.width, x.height), (y.width, y.height), "sizes differ");
    let (mut abs, mut rel, mut same) = (0f64, 0f64, 0usize);
    for (p, q) in x.data.iter().zip(&y.data) {
        if p == q {
            same += 1;
        }
        for c in 0..3 {
            let d = (p[c] as f64 - q[c] as f64).abs();
            abs = abs.max(d);
            rel = rel.max(d / (q[c].abs() as f64).max(1e-3));
        }
    }
    println!(
        "max abs {abs:.3e}, max rel {rel:.3e}, identical pixels {same}/{}",
        x.data.len()
    );
}
