//! Reports: result tables (CSV/JSON), log-log error plots (PNG and SVG, plotters with the
//! DejaVu Sans font shipped in assets/fonts), side-by-side crops, and the HTML report of
//! an experiment's results ([`html`]).

pub mod html;

use crate::image_io::{srgb_encode, RgbImage};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::FontStyle;
use std::path::Path;
use std::sync::Once;

static FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");

fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // The font is compiled in; a failure here would be a corrupt asset.
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    });
}

/// One line of a plot: points, and optionally each point's spread (low, high) in y,
/// drawn as an error bar (the range over seeds).
pub struct Series {
    pub name: String,
    pub points: Vec<(f64, f64)>,
    pub spread: Vec<(f64, f64)>,
}

/// One panel of a figure.
pub struct Panel {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub series: Vec<Series>,
}

fn range(vals: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in vals.filter(|v| v.is_finite() && *v > 0.0) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return (0.1, 1.0);
    }
    if hi <= lo * 1.0001 {
        return (lo / 1.5, hi * 1.5);
    }
    (lo / 1.15, hi * 1.15)
}

/// Ticks of a log axis over [lo, hi]: 1-2-5 of every decade, thinned to powers of ten
/// when there are many, 1-2-3-5 or all nine steps when the range holds fewer than three:
/// every axis gets labels, also one narrower than a decade.
pub fn log_ticks(lo: f64, hi: f64) -> Vec<f64> {
    if !(lo > 0.0 && hi >= lo && hi.is_finite()) {
        return vec![];
    }
    let of = |ms: &[f64]| -> Vec<f64> {
        let (e0, e1) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
        (e0..=e1)
            .flat_map(|e| ms.iter().map(move |m| m * 10f64.powi(e)))
            .filter(|v| *v >= lo * (1.0 - 1e-9) && *v <= hi * (1.0 + 1e-9))
            .collect()
    };
    let t = of(&[1.0, 2.0, 5.0]);
    if t.len() > 10 {
        return of(&[1.0]);
    }
    if t.len() < 3 {
        for ms in [
            &[1.0, 2.0, 3.0, 5.0][..],
            &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0],
        ] {
            let more = of(ms);
            if more.len() >= 3 {
                return more;
            }
        }
        // narrower than one step: the ends and the middle
        let mid = (lo * hi).sqrt();
        return vec![lo, mid, hi];
    }
    t
}

/// An axis label as people write it: "100", "1000", "0.5", "0.025", "2.5e-5".
pub fn tick_label(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let a = v.abs();
    if !(1e-3..1e6).contains(&a) {
        let s = format!("{v:.1e}");
        return s.replace(".0e", "e");
    }
    // three significant digits, trailing zeros dropped
    let decimals = (2 - a.log10().floor() as i32).max(0) as usize;
    let s = format!("{v:.decimals$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

fn draw_panel<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, p: &Panel) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    let (x0, x1) = range(p.series.iter().flat_map(|s| s.points.iter().map(|q| q.0)));
    let (y0, y1) = range(p.series.iter().flat_map(|s| {
        s.points
            .iter()
            .map(|q| q.1)
            .chain(s.spread.iter().flat_map(|q| [q.0, q.1]))
    }));
    let mut chart = ChartBuilder::on(area)
        .caption(&p.title, ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(48)
        .y_label_area_size(72)
        .build_cartesian_2d(
            (x0..x1).log_scale().with_key_points(log_ticks(x0, x1)),
            (y0..y1).log_scale().with_key_points(log_ticks(y0, y1)),
        )
        .map_err(e)?;
    chart
        .configure_mesh()
        .x_desc(&p.x_label)
        .y_desc(&p.y_label)
        .label_style(("sans-serif", 14))
        .axis_desc_style(("sans-serif", 16))
        .x_label_formatter(&|v| tick_label(*v))
        .y_label_formatter(&|v| tick_label(*v))
        .draw()
        .map_err(e)?;
    for (i, s) in p.series.iter().enumerate() {
        let color = Palette99::pick(i).to_rgba();
        let pts: Vec<(f64, f64)> = s
            .points
            .iter()
            .copied()
            .filter(|q| q.0 > 0.0 && q.1 > 0.0)
            .collect();
        chart
            .draw_series(LineSeries::new(pts.clone(), color.stroke_width(2)))
            .map_err(e)?
            .label(&s.name)
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
            });
        chart
            .draw_series(pts.iter().map(|&q| Circle::new(q, 4, color.filled())))
            .map_err(e)?;
        let bars = s
            .points
            .iter()
            .zip(&s.spread)
            .filter(|(q, b)| q.0 > 0.0 && b.0 > 0.0 && b.1 > 0.0 && b.1 > b.0);
        chart
            .draw_series(bars.map(|(q, b)| {
                ErrorBar::new_vertical(q.0, b.0, q.1.clamp(b.0, b.1), b.1, color.stroke_width(1), 8)
            }))
            .map_err(e)?;
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 15))
        .position(SeriesLabelPosition::UpperRight)
        .draw()
        .map_err(e)?;
    Ok(())
}

fn draw_figure<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    panels: &[Panel],
) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let areas = root.split_evenly((1, panels.len().max(1)));
    for (a, p) in areas.iter().zip(panels) {
        draw_panel(a, p)?;
    }
    root.present().map_err(|e| e.to_string())
}

/// A figure of log-log panels side by side, written as `stem.png` and `stem.svg`.
pub fn plot_panels(stem: &Path, panels: &[Panel]) -> Result<(), String> {
    register_font();
    let size = (620 * panels.len().max(1) as u32, 480);
    let png = stem.with_extension("png");
    let svg = stem.with_extension("svg");
    // drawn in memory, written in one call whose error is seen (plotters' file
    // backends write on drop, where a full disk goes unnoticed)
    let mut rgb = vec![0u8; size.0 as usize * size.1 as usize * 3];
    draw_figure(
        BitMapBackend::with_buffer(&mut rgb, size).into_drawing_area(),
        panels,
    )
    .map_err(|e| format!("{}: {e}", png.display()))?;
    crate::image_io::write_png_rgb8(&png, size.0, size.1, &rgb)?;
    let mut text = String::new();
    draw_figure(
        SVGBackend::with_string(&mut text, size).into_drawing_area(),
        panels,
    )
    .map_err(|e| format!("{}: {e}", svg.display()))?;
    std::fs::write(&svg, text).map_err(|e| format!("{}: {e}", svg.display()))
}

/// Crop (x, y, w, h) of an image, clipped to it.
pub fn crop(img: &RgbImage, c: [u32; 4]) -> RgbImage {
    let x0 = c[0].min(img.width.saturating_sub(1));
    let y0 = c[1].min(img.height.saturating_sub(1));
    let w = c[2].min(img.width - x0).max(1);
    let h = c[3].min(img.height - y0).max(1);
    let mut data = Vec::with_capacity((w * h) as usize);
    for y in y0..y0 + h {
        for x in x0..x0 + w {
            data.push(img.get(x, y));
        }
    }
    RgbImage::new(w, h, data)
}

/// Tiles side by side, each scaled up by `zoom`, labelled underneath; sRGB PNG.
pub fn side_by_side(
    path: &Path,
    tiles: &[(String, RgbImage)],
    zoom: u32,
    exposure: f32,
) -> Result<(), String> {
    register_font();
    let zoom = zoom.max(1);
    let (w, h) = (
        tiles.iter().map(|t| t.1.width).max().unwrap_or(1),
        tiles.iter().map(|t| t.1.height).max().unwrap_or(1),
    );
    let full = side_by_side_size(tiles.len(), w, h, zoom);
    if full.0.max(full.1) > MAX_SIDE_BY_SIDE {
        return Err(format!(
            "{}: the side-by-side image would be {}x{} pixels, more than {MAX_SIDE_BY_SIDE} on a side: use a smaller crop or zoom",
            path.display(),
            full.0,
            full.1
        ));
    }
    let (tw, th) = (w * zoom, h * zoom);
    let size = (full.0 as u32, full.1 as u32);
    // drawn in memory and written by image_io, which reports write errors
    let mut rgb = vec![0u8; size.0 as usize * size.1 as usize * 3];
    draw_tiles(&mut rgb, size, tiles, zoom, exposure, (tw, th))
        .map_err(|e| format!("{}: {e}", path.display()))?;
    crate::image_io::write_png_rgb8(path, size.0, size.1, &rgb)
}

/// The tiles and their labels of [`side_by_side`], drawn into an RGB buffer.
fn draw_tiles(
    rgb: &mut [u8],
    size: (u32, u32),
    tiles: &[(String, RgbImage)],
    zoom: u32,
    exposure: f32,
    (tw, th): (u32, u32),
) -> Result<(), String> {
    let gap = SIDE_BY_SIDE_GAP;
    let root = BitMapBackend::with_buffer(rgb, size).into_drawing_area();
    let e = |e: DrawingAreaErrorKind<_>| e.to_string();
    root.fill(&WHITE).map_err(e)?;
    let k = 2f32.powf(exposure);
    for (i, (name, img)) in tiles.iter().enumerate() {
        let ox = gap + i as u32 * (tw + gap);
        for y in 0..img.height * zoom {
            for x in 0..img.width * zoom {
                let p = img.get(x / zoom, y / zoom);
                let c = |v: f32| (srgb_encode(v * k).clamp(0.0, 1.0) * 255.0 + 0.5) as u8;
                root.draw_pixel(
                    ((ox + x) as i32, (gap + y) as i32),
                    &RGBColor(c(p[0]), c(p[1]), c(p[2])),
                )
                .map_err(e)?;
            }
        }
        root.draw_text(
            name,
            &("sans-serif", 16).into_text_style(&root),
            (ox as i32 + 2, (gap + th + 6) as i32),
        )
        .map_err(e)?;
    }
    root.present().map_err(e)
}

/// The largest side, in pixels, of a [`side_by_side`] image (16384: 768 MiB of RGB at
/// most): a crop zoomed without bound would take the machine's memory.
pub const MAX_SIDE_BY_SIDE: u64 = 16384;
const SIDE_BY_SIDE_LABEL: u32 = 28;
const SIDE_BY_SIDE_GAP: u32 = 6;

/// (width, height) in pixels of the [`side_by_side`] image of `n` tiles of at most
/// `w` x `h` pixels each, scaled by `zoom` (in u64: no overflow for any input).
pub fn side_by_side_size(n: usize, w: u32, h: u32, zoom: u32) -> (u64, u64) {
    let (n, zoom, gap) = (n.max(1) as u64, zoom.max(1) as u64, SIDE_BY_SIDE_GAP as u64);
    (
        n * w as u64 * zoom + (n + 1) * gap,
        h as u64 * zoom + SIDE_BY_SIDE_LABEL as u64 + 2 * gap,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn writes_plots_and_tiles() {
        let dir = std::env::temp_dir().join(format!("kalos-report-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let panel = Panel {
            title: "RMSE".into(),
            x_label: "seconds".into(),
            y_label: "rmse".into(),
            series: vec![
                Series {
                    name: "path".into(),
                    points: vec![(1.0, 0.1), (2.0, 0.07), (4.0, 0.05)],
                    spread: vec![(0.09, 0.11), (0.06, 0.08), (0.045, 0.055)],
                },
                Series {
                    name: "dtf".into(),
                    points: vec![(1.0, 0.05), (2.0, 0.035), (4.0, 0.025)],
                    spread: vec![],
                },
            ],
        };
        plot_panels(&dir.join("plot"), &[panel]).unwrap();
        let svg = std::fs::read_to_string(dir.join("plot.svg")).unwrap();
        assert!(svg.contains("dtf") && svg.contains("seconds"));
        // y ticks inside one decade (0.025 .. 0.11 spans no power of ten): labelled
        // (plotters writes a text element's content on a line of its own)
        assert!(svg.contains("\n0.05\n") && svg.contains("\n0.1\n"), "{svg}");
        // x ticks as numbers are written
        assert!(svg.contains("\n2\n") && !svg.contains("2.000"), "{svg}");
        assert!(std::fs::metadata(dir.join("plot.png")).unwrap().len() > 1000);
        let img = RgbImage::new(4, 4, vec![[0.5, 0.2, 0.1]; 16]);
        let c = crop(&img, [1, 1, 10, 2]);
        assert_eq!((c.width, c.height), (3, 2));
        side_by_side(
            &dir.join("tiles.png"),
            &[("a".into(), c.clone()), ("b".into(), c)],
            4,
            0.0,
        )
        .unwrap();
        let back = crate::image_io::read_image(&dir.join("tiles.png")).unwrap();
        assert!(back.width > 24);
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn axis_ticks_and_labels_read_as_numbers() {
        assert_eq!(tick_label(100.0), "100");
        assert_eq!(tick_label(1000.0), "1000");
        assert_eq!(tick_label(0.5), "0.5");
        assert_eq!(tick_label(0.025), "0.025");
        assert_eq!(tick_label(2.5e-5), "2.5e-5");
        assert_eq!(tick_label(1e-4), "1e-4");
        assert_eq!(
            log_ticks(16.0, 1024.0),
            vec![20.0, 50.0, 100.0, 200.0, 500.0, 1000.0]
        );
        // inside one decade: 1-2-3-5, else the nine steps
        assert_eq!(log_ticks(0.08, 0.45), vec![0.1, 0.2, 0.30000000000000004]);
        assert_eq!(log_ticks(0.02, 0.08).len(), 3);
        assert_eq!(log_ticks(0.06, 0.095).len(), 4);
        // narrower than a step: still three labels
        assert_eq!(log_ticks(0.021, 0.029).len(), 3);
    }

    /// /dev/full fails every write, as a full disk does: plots and tiles say so.
    #[cfg(target_os = "linux")]
    #[test]
    fn write_errors_are_reported() {
        let dir = std::env::temp_dir().join(format!("kalos-report-full-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        for name in ["p.png", "p.svg", "t.png"] {
            std::os::unix::fs::symlink("/dev/full", dir.join(name)).unwrap();
        }
        let panel = Panel {
            title: "RMSE".into(),
            x_label: "s".into(),
            y_label: "rmse".into(),
            series: vec![Series {
                name: "a".into(),
                points: vec![(1.0, 1.0), (2.0, 0.5)],
                spread: vec![],
            }],
        };
        let e = plot_panels(&dir.join("p"), &[panel]).unwrap_err();
        assert!(e.contains("p.png"), "{e}");
        std::fs::remove_file(dir.join("p.png")).unwrap();
        let panel = Panel {
            title: "RMSE".into(),
            x_label: "s".into(),
            y_label: "rmse".into(),
            series: vec![Series {
                name: "a".into(),
                points: vec![(1.0, 1.0), (2.0, 0.5)],
                spread: vec![],
            }],
        };
        let e = plot_panels(&dir.join("p"), &[panel]).unwrap_err();
        assert!(e.contains("p.svg"), "{e}");
        let tile = RgbImage::new(2, 2, vec![[0.5; 3]; 4]);
        let e = side_by_side(&dir.join("t.png"), &[("a".into(), tile)], 2, 0.0).unwrap_err();
        assert!(e.contains("t.png"), "{e}");
        // and a zoom without bound is refused before anything is allocated
        let tile = RgbImage::new(8, 8, vec![[0.5; 3]; 64]);
        let e = side_by_side(&dir.join("u.png"), &[("a".into(), tile)], 100_000, 0.0).unwrap_err();
        assert!(e.contains("side-by-side"), "{e}");
        std::fs::remove_dir_all(&dir).ok();
    }
}
