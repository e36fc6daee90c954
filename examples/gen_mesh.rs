//! Writes a large OBJ for the loading/BVH/memory benchmark (docs/results/throughput.md):
//! a closed room (inward-facing walls, one ceiling light) holding a grid of finely
//! tessellated bumpy spheres. `cargo run --release --example gen_mesh -- OUT.obj [TRIANGLES]`
use std::f32::consts::PI;
use std::fmt::Write as _;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let out = args.get(1).cloned().unwrap_or_else(|| "big.obj".into());
    let target: usize = args
        .get(2)
        .and_then(|s| s.parse().ok())
        .unwrap_or(1_000_000);
    let spheres = 16usize; // 4 x 4 grid
                           // a UV sphere with r rings and 2r segments has about 4 r^2 triangles
    let rings = (((target / spheres) as f32 / 4.0).sqrt()) as usize;
    let segs = 2 * rings;
    let mut s = String::with_capacity(target * 60);
    let mtl = std::path::Path::new(&out).with_extension("mtl");
    writeln!(s, "mtllib {}", mtl.file_name().unwrap().to_str().unwrap()).unwrap();
    let mut nv = 0usize;
    // room: x, z in [-5, 5], y in [0, 6]; quads wound to face inwards
    let room = [
        [[-5., 0., -5.], [5., 0., -5.], [5., 0., 5.], [-5., 0., 5.]], // floor (faces +y)
        [[-5., 6., -5.], [-5., 6., 5.], [5., 6., 5.], [5., 6., -5.]], // ceiling (faces -y)
        [[-5., 0., -5.], [-5., 6., -5.], [5., 6., -5.], [5., 0., -5.]], // back (faces +z)
        [[-5., 0., 5.], [5., 0., 5.], [5., 6., 5.], [-5., 6., 5.]],   // front (faces -z)
        [[-5., 0., -5.], [-5., 0., 5.], [-5., 6., 5.], [-5., 6., -5.]], // left (faces +x)
        [[5., 0., -5.], [5., 6., -5.], [5., 6., 5.], [5., 0., 5.]],   // right (faces -x)
    ];
    writeln!(s, "usemtl wall").unwrap();
    for q in room {
        for v in q {
            writeln!(s, "v {} {} {}", v[0], v[1], v[2]).unwrap();
        }
        writeln!(s, "f {} {} {} {}", nv + 1, nv + 2, nv + 3, nv + 4).unwrap();
        nv += 4;
    }
    writeln!(s, "usemtl light").unwrap();
    for v in [
        [-1., 5.99, -1.],
        [-1., 5.99, 1.],
        [1., 5.99, 1.],
        [1., 5.99, -1.],
    ] {
        writeln!(s, "v {} {} {}", v[0], v[1], v[2]).unwrap();
    }
    writeln!(s, "f {} {} {} {}", nv + 1, nv + 2, nv + 3, nv + 4).unwrap();
    nv += 4;
    writeln!(s, "usemtl ball").unwrap();
    for i in 0..spheres {
        let c = [
            -3.0 + 2.0 * (i % 4) as f32,
            1.2,
            -3.0 + 2.0 * (i / 4) as f32,
        ];
        let base = nv;
        for r in 0..=rings {
            let th = PI * r as f32 / rings as f32;
            for k in 0..segs {
                let ph = 2.0 * PI * k as f32 / segs as f32;
                let bump = 0.8 + 0.05 * (7.0 * th).sin() * (5.0 * ph).cos();
                let p = [
                    c[0] + bump * th.sin() * ph.cos(),
                    c[1] + bump * th.cos(),
                    c[2] + bump * th.sin() * ph.sin(),
                ];
                writeln!(s, "v {:.5} {:.5} {:.5}", p[0], p[1], p[2]).unwrap();
                nv += 1;
            }
        }
        let id = |r: usize, k: usize| base + r * segs + (k % segs) + 1;
        for r in 0..rings {
            for k in 0..segs {
                let (a, b, cc, d) = (id(r, k), id(r + 1, k), id(r + 1, k + 1), id(r, k + 1));
                writeln!(s, "f {a} {b} {cc}").unwrap();
                writeln!(s, "f {a} {cc} {d}").unwrap();
            }
        }
    }
    std::fs::write(&out, s).unwrap();
    std::fs::write(mtl, "newmtl wall\nKd 0.7 0.7 0.7\nnewmtl light\nKd 0 0 0\nKe 20 20 20\nnewmtl ball\nKd 0.6 0.4 0.3\nKs 0.3 0.3 0.3\nNs 40\n").unwrap();
    eprintln!(
        "wrote {out}: {} spheres of {} triangles",
        spheres,
        2 * rings * segs
    );
}
