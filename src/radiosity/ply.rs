//! The meshed radiosity solution as an ASCII PLY with per-vertex colours (MeshLab and
//! Blender read `red green blue` uchar vertex properties).
//!
//! Colour: the radiance B / pi of the brighter side of each vertex (the side that faces
//! the light in a closed room), linear RGB from the bands, scaled so that the mean over
//! vertices of non-emitting surfaces maps to 0.18 (a middle grey), then x / (1 + x)
//! (Reinhard) and the sRGB transfer curve.

use super::Solution;
use crate::spectrum::Spectrum;
use std::io::Write;
use std::path::Path;

fn to_rgb(b: &[f32]) -> [f32; 3] {
    match b.len() {
        3 => [b[0], b[1], b[2]],
        8 => {
            let mut s = [0.0; 8];
            s.copy_from_slice(b);
            Spectrum::<8>(s).to_rgb()
        }
        16 => {
            let mut s = [0.0; 16];
            s.copy_from_slice(b);
            Spectrum::<16>(s).to_rgb()
        }
        _ => [0.0; 3],
    }
}

fn srgb(x: f32) -> u8 {
    let x = x.clamp(0.0, 1.0);
    let y = if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    };
    (y * 255.0 + 0.5) as u8
}

/// Tone-mapped vertex colours (sRGB bytes), one per welded vertex.
pub fn vertex_colours(sol: &Solution) -> Vec<[u8; 3]> {
    let nb = sol.bands;
    let nv = sol.mesh.verts.len();
    // radiance of the brighter side, and whether any element at the vertex emits
    let mut emits = vec![false; nv];
    for e in &sol.mesh.elems {
        if sol.tri_e[e.prim as usize].iter().any(|&v| v > 0.0) {
            for &v in &e.v {
                emits[v as usize] = true;
            }
        }
    }
    let rad: Vec<[f32; 3]> = (0..nv)
        .map(|v| {
            let f = to_rgb(&sol.vertex_b[(2 * v) * nb..(2 * v + 1) * nb]);
            let b = to_rgb(&sol.vertex_b[(2 * v + 1) * nb..(2 * v + 2) * nb]);
            let lum = |c: [f32; 3]| Spectrum::<3>(c).luminance();
            let c = if lum(f) >= lum(b) { f } else { b };
            c.map(|x| x * std::f32::consts::FRAC_1_PI)
        })
        .collect();
    let (mut sum, mut n) = (0.0f64, 0usize);
    for (c, &e) in rad.iter().zip(&emits) {
        if !e {
            sum += Spectrum::<3>(*c).luminance() as f64;
            n += 1;
        }
    }
    let mean = if n > 0 { sum / n as f64 } else { 1.0 };
    let k = if mean > 0.0 {
        (0.18 / mean) as f32
    } else {
        1.0
    };
    rad.iter()
        .map(|c| c.map(|x| srgb(x * k / (1.0 + x * k))))
        .collect()
}

/// Write the mesh and its colours.
pub fn write_ply(sol: &Solution, path: &Path) -> Result<(), String> {
    let colours = vertex_colours(sol);
    let f = std::fs::File::create(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut w = std::io::BufWriter::new(f);
    let err = |e: std::io::Error| format!("{}: {e}", path.display());
    write!(
        w,
        "ply\nformat ascii 1.0\ncomment kalos radiosity solution: radiance B/pi, tone-mapped sRGB\n\
         element vertex {}\nproperty float x\nproperty float y\nproperty float z\n\
         property uchar red\nproperty uchar green\nproperty uchar blue\n\
         element face {}\nproperty list uchar int vertex_indices\nend_header\n",
        sol.mesh.verts.len(),
        sol.mesh.elems.len()
    )
    .map_err(err)?;
    for (p, c) in sol.mesh.verts.iter().zip(&colours) {
        writeln!(w, "{} {} {} {} {} {}", p.x, p.y, p.z, c[0], c[1], c[2]).map_err(err)?;
    }
    for e in &sol.mesh.elems {
        // wound like the scene triangle (upper cells are stored reversed)
        let [a, b, c] = e.v;
        let (b, c) = if e.e1.cross(e.e2).dot(e.n) >= 0.0 {
            (b, c)
        } else {
            (c, b)
        };
        writeln!(w, "3 {a} {b} {c}").map_err(err)?;
    }
    w.flush().map_err(err)
}
