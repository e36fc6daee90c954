//! Diagnostic: print pixel values of images. `cargo run --example img_px -- X Y A.exr B.exr ...`
fn main() {
    let a: Vec<String> = std::env::args().collect();
    let (x, y): (u32, u32) = (a[1].parse().unwrap(), a[2].parse().unwrap());
    for f in &a[3..] {
        let img = kalos::image_io::read_image(std::path::Path::new(f)).unwrap();
        println!("{f}: {:?}", img.data[(y * img.width + x) as usize]);
    }
}
