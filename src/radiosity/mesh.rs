//! The radiosity mesh: every diffuse-like or emissive scene triangle split 4-way, level by
//! level, until its elements are no larger than the maximum element area. A triangle at
//! level k is the regular grid of n = 2^k steps along two edges (exactly what k rounds of
//! 4-way splitting give), so a hit point finds its element and barycentrics in O(1).
//! Vertices are welded across triangles (same position, same plane orientation, same
//! material): a wall's elements share corners and its radiosity is continuous.

use crate::math::Vec3;
use std::collections::HashMap;

/// Largest subdivision level of one triangle (4^15 elements already exceed any budget).
pub const MAX_LEVEL: u32 = 15;

/// One element (a small triangle) of the mesh.
#[derive(Clone, Copy, Debug)]
pub struct Element {
    /// Welded vertex indices.
    pub v: [u32; 3],
    /// The scene triangle it lies on.
    pub prim: u32,
    pub area: f32,
    /// Unit normal of the scene triangle's winding (its front side).
    pub n: Vec3,
    /// Centroid: where the element receives.
    pub c: Vec3,
    /// Corner and edges: source points are spread over p0 + a e1 + b e2.
    pub p0: Vec3,
    pub e1: Vec3,
    pub e2: Vec3,
}

/// How one scene triangle was meshed.
#[derive(Clone, Copy, Debug)]
pub struct TriMesh {
    pub level: u32,
    /// Index of its first element; its n^2 elements follow (lower cells, then upper).
    pub first_elem: u32,
    /// Offset of its (n+1)(n+2)/2 grid vertices in `Mesh::grid`.
    pub first_grid: u32,
    pub v0: Vec3,
    pub e1: Vec3,
    pub e2: Vec3,
}

/// The meshed scene.
#[derive(Clone, Debug, Default)]
pub struct Mesh {
    pub verts: Vec<Vec3>,
    pub elems: Vec<Element>,
    /// Per scene triangle: its meshing, None if it takes no part (mirror, glass, black).
    pub tris: Vec<Option<TriMesh>>,
    /// Grid vertex -> welded vertex, per meshed triangle.
    pub grid: Vec<u32>,
}

/// Index of grid vertex (i, j), i + j <= n, in a triangle's grid table.
#[inline]
pub fn grid_index(n: u32, i: u32, j: u32) -> u32 {
    j * (n + 1) - j * j.saturating_sub(1) / 2 + i
}

/// Index of cell (i, j) among a triangle's n^2 elements: lower cells (i + j <= n - 1)
/// first, row by row, then upper cells (i + j <= n - 2).
#[inline]
pub fn cell_index(n: u32, i: u32, j: u32, upper: bool) -> u32 {
    if upper {
        n * (n + 1) / 2 + j * (n - 1) - j * j.saturating_sub(1) / 2 + i
    } else {
        j * n - j * j.saturating_sub(1) / 2 + i
    }
}

/// The level k at which a triangle of area `a` has elements of area <= `max_area`.
pub fn level_for(a: f64, max_area: f64) -> u32 {
    let mut k = 0;
    let mut e = a;
    while e > max_area && k <= MAX_LEVEL {
        e /= 4.0;
        k += 1;
    }
    k
}

/// Element and vertex counts the mesh will have (vertices before welding, an upper bound).
pub fn count(levels: &[Option<u32>]) -> (u64, u64) {
    let mut elems = 0u64;
    let mut verts = 0u64;
    for &l in levels.iter().flatten() {
        let n = 1u64 << l.min(31);
        elems = elems.saturating_add(n * n);
        verts = verts.saturating_add((n + 1) * (n + 2) / 2);
    }
    (elems, verts)
}

/// Build the mesh. `levels[t]` is triangle t's level (None: not meshed); `weld_key[t]`
/// the material-like key that must match for vertices to weld; `scale` the scene's size.
pub fn build(tris: &[[Vec3; 3]], levels: &[Option<u32>], weld_key: &[u32], scale: f32) -> Mesh {
    let (ne, nv) = count(levels);
    let mut m = Mesh {
        verts: Vec::with_capacity(nv as usize),
        elems: Vec::with_capacity(ne as usize),
        tris: vec![None; tris.len()],
        grid: Vec::with_capacity(nv as usize),
    };
    let eps = (scale.max(1e-12) * 1e-5) as f64;
    let mut weld: HashMap<([i64; 3], [i32; 3], u32), u32> = HashMap::new();
    for (t, tri) in tris.iter().enumerate() {
        let Some(level) = levels[t] else { continue };
        let n = 1u32 << level;
        let (v0, e1, e2) = (tri[0], tri[1] - tri[0], tri[2] - tri[0]);
        let cr = e1.cross(e2);
        let normal = cr.normalize_or_zero();
        let nkey = [
            (normal.x * 64.0).round() as i32,
            (normal.y * 64.0).round() as i32,
            (normal.z * 64.0).round() as i32,
        ];
        let first_grid = m.grid.len() as u32;
        for j in 0..=n {
            for i in 0..=(n - j) {
                let p = v0 + e1 * (i as f32 / n as f32) + e2 * (j as f32 / n as f32);
                let q = [
                    (p.x as f64 / eps).round() as i64,
                    (p.y as f64 / eps).round() as i64,
                    (p.z as f64 / eps).round() as i64,
                ];
                let next = m.verts.len() as u32;
                let id = *weld.entry((q, nkey, weld_key[t])).or_insert(next);
                if id == next {
                    m.verts.push(p);
                }
                m.grid.push(id);
            }
        }
        let first_elem = m.elems.len() as u32;
        let area = 0.5 * cr.length() / (n * n) as f32;
        let (s1, s2) = (e1 / n as f32, e2 / n as f32);
        let g = |i: u32, j: u32| m.grid[(first_grid + grid_index(n, i, j)) as usize];
        let mut cells = Vec::with_capacity((n * n) as usize);
        // lower cells (i, j), (i+1, j), (i, j+1)
        for j in 0..n {
            for i in 0..(n - j) {
                let p0 = v0 + s1 * i as f32 + s2 * j as f32;
                cells.push(Element {
                    v: [g(i, j), g(i + 1, j), g(i, j + 1)],
                    prim: t as u32,
                    area,
                    n: normal,
                    c: p0 + (s1 + s2) / 3.0,
                    p0,
                    e1: s1,
                    e2: s2,
                });
            }
        }
        // upper cells (i+1, j), (i+1, j+1), (i, j+1): corner (i+1, j+1), edges -s1, -s2
        for j in 0..n.saturating_sub(1) {
            for i in 0..(n - 1 - j) {
                let p0 = v0 + s1 * (i + 1) as f32 + s2 * (j + 1) as f32;
                cells.push(Element {
                    v: [g(i + 1, j), g(i + 1, j + 1), g(i, j + 1)],
                    prim: t as u32,
                    area,
                    n: normal,
                    c: p0 - (s1 + s2) / 3.0,
                    p0,
                    e1: -s1,
                    e2: -s2,
                });
            }
        }
        debug_assert_eq!(cells.len() as u32, n * n);
        m.elems.extend(cells);
        m.tris[t] = Some(TriMesh {
            level,
            first_elem,
            first_grid,
            v0,
            e1,
            e2,
        });
    }
    m
}

/// Where a point with barycentrics (b1, b2) of a triangle meshed at `level` falls: its
/// element (relative to the triangle's first) and the grid vertices (i, j) with weights.
#[inline]
pub fn locate(level: u32, b1: f32, b2: f32) -> (u32, [(u32, u32, f32); 3]) {
    let n = 1u32 << level;
    let nf = n as f32;
    let x = (b1 * nf).clamp(0.0, nf);
    let y = (b2 * nf).clamp(0.0, nf);
    let j = (y.floor() as u32).min(n - 1);
    let i = (x.floor() as u32).min(n - 1 - j);
    let fx = (x - i as f32).clamp(0.0, 1.0);
    let fy = (y - j as f32).clamp(0.0, 1.0);
    if fx + fy <= 1.0 || i + j + 1 >= n {
        // lower cell; beyond the hypotenuse (rounding) the weights are renormalised
        let s = (fx + fy).max(1.0);
        let (fx, fy) = (fx / s, fy / s);
        (
            cell_index(n, i, j, false),
            [(i, j, 1.0 - fx - fy), (i + 1, j, fx), (i, j + 1, fy)],
        )
    } else {
        (
            cell_index(n, i, j, true),
            [
                (i + 1, j, 1.0 - fy),
                (i + 1, j + 1, fx + fy - 1.0),
                (i, j + 1, 1.0 - fx),
            ],
        )
    }
}

/// The element (relative to the triangle's first) of the point with barycentrics (b1,
/// b2) of a triangle meshed at `level`, as `locate` finds it but without its corners'
/// weights, and by truncation (the coordinates are clamped non-negative) rather than
/// a call of `floor`: the roulette's lookup at every rouletted vertex.
#[inline]
pub fn cell_of(level: u32, b1: f32, b2: f32) -> u32 {
    let n = 1u32 << level;
    let nf = n as f32;
    let x = (b1 * nf).clamp(0.0, nf);
    let y = (b2 * nf).clamp(0.0, nf);
    let j = (y as u32).min(n - 1);
    let i = (x as u32).min(n - 1 - j);
    let (fx, fy) = (x - i as f32, y - j as f32);
    cell_index(n, i, j, fx + fy > 1.0 && i + j + 1 < n)
}

/// Barycentrics (b1, b2) of `p` in the triangle v0 + b1 e1 + b2 e2 (p projected on its plane).
#[inline]
pub fn barycentrics(v0: Vec3, e1: Vec3, e2: Vec3, p: Vec3) -> (f32, f32) {
    let d = p - v0;
    let (d00, d01, d11) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    let (d20, d21) = (d.dot(e1), d.dot(e2));
    let den = d00 * d11 - d01 * d01;
    if den <= 0.0 {
        return (0.0, 0.0);
    }
    ((d11 * d20 - d01 * d21) / den, (d00 * d21 - d01 * d20) / den)
}
