//! The memory a large mesh's scene build takes at its peak (the BVH build), counted by
//! this test binary's own allocator: a mesh without shading normals or texture
//! coordinates must not pay for them per triangle while its BVH is built.

use kalos::math::Vec3;
use kalos::scene::{CameraDesc, MaterialDesc, Scene, SceneDesc};
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

/// The system allocator, counting the bytes live and their peak.
struct Counting;

static LIVE: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let p = System.alloc(layout);
        if !p.is_null() {
            let now = LIVE.fetch_add(layout.size(), Ordering::Relaxed) + layout.size();
            PEAK.fetch_max(now, Ordering::Relaxed);
        }
        p
    }

    unsafe fn dealloc(&self, p: *mut u8, layout: Layout) {
        LIVE.fetch_sub(layout.size(), Ordering::Relaxed);
        System.dealloc(p, layout)
    }
}

#[global_allocator]
static ALLOC: Counting = Counting;

/// A height field of `n` x `n` quads (two triangles each), with no normals and no uvs,
/// its per-triangle vectors allocated to their length.
fn height_field(n: usize) -> SceneDesc {
    let tris = 2 * n * n;
    let mut d = SceneDesc {
        name: "height field".into(),
        materials: vec![MaterialDesc::named("ground")],
        camera: Some(CameraDesc {
            origin: [0.0, 2.0, 2.0],
            ..Default::default()
        }),
        positions: Vec::with_capacity(tris),
        normals: Vec::with_capacity(tris),
        uvs: Vec::with_capacity(tris),
        material: Vec::with_capacity(tris),
        ..Default::default()
    };
    let p = |i: usize, j: usize| {
        let (x, z) = (i as f32 / n as f32, j as f32 / n as f32);
        Vec3::new(x, 0.05 * (7.0 * x).sin() * (5.0 * z).cos(), z)
    };
    for i in 0..n {
        for j in 0..n {
            let (a, b, c, e) = (p(i, j), p(i + 1, j), p(i + 1, j + 1), p(i, j + 1));
            d.push_triangle([a, c, b], None, None, 0);
            d.push_triangle([a, e, c], None, None, 0);
        }
    }
    d
}

/// At its peak the build holds the triangles (36 bytes each) and their materials (4),
/// the BVH builder's boxes and indices (36), its binary nodes and their compacted copy
/// (2 x 64) and a little more: 220 bytes a triangle measured. The description's optional
/// normals and uvs (40 and 28 bytes a triangle, all absent) held through the build added 68.
#[test]
fn a_mesh_without_normals_or_uvs_builds_in_under_240_bytes_a_triangle() {
    let n = 300;
    let d = height_field(n);
    let tris = d.positions.len();
    assert_eq!(tris, 2 * n * n);
    PEAK.store(LIVE.load(Ordering::Relaxed), Ordering::Relaxed);
    let scene = Scene::build(d, 0.0).unwrap();
    let per_tri = PEAK.load(Ordering::Relaxed) as f64 / tris as f64;
    assert_eq!(scene.tris.len(), tris);
    assert!(
        per_tri < 240.0,
        "{per_tri:.1} bytes a triangle at the build's peak"
    );
}
