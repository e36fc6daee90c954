//! Diagnostic: the pixels that carry most of an image's squared error against a reference.
//! `cargo run --release --example img_worst -- IMAGE.exr REFERENCE.exr [K] [rel]`
//! (`rel`: rank by relative error ||x - y|| / ||y|| instead).
fn main() {
    let a: Vec<String> = std::env::args().collect();
    let img = kalos::image_io::read_image(std::path::Path::new(&a[1])).unwrap();
    let r = kalos::image_io::read_image(std::path::Path::new(&a[2])).unwrap();
    let k: usize = a.get(3).map(|s| s.parse().unwrap()).unwrap_or(10);
    let rel = a.get(4).map(|s| s == "rel").unwrap_or(false);
    let mut e: Vec<(f64, usize)> = (0..r.data.len())
        .map(|i| {
            let (x, y) = (img.data[i], r.data[i]);
            let d = (0..3).map(|c| ((x[c] - y[c]) as f64).powi(2)).sum::<f64>();
            let n = (0..3).map(|c| (y[c] as f64).abs()).sum::<f64>().max(1e-6);
            (if rel { d.sqrt() / n } else { d }, i)
        })
        .collect();
    let total: f64 = e.iter().map(|v| v.0).sum();
    e.sort_by(|a, b| b.0.total_cmp(&a.0));
    for &(err, i) in e.iter().take(k) {
        println!(
            "({:>3},{:>3}) share {:.3} image {:?} reference {:?}",
            i as u32 % r.width,
            i as u32 / r.width,
            err / total,
            img.data[i],
            r.data[i]
        );
    }
}
