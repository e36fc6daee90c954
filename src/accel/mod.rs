//! Ray–triangle acceleration structure.
//!
//! Build: binned SAH (16 bins, all three axes, costs counted in 4-triangle
//! blocks) into a flattened BVH2 of 32-byte nodes, subtrees built in parallel
//! with rayon; the BVH2 is then collapsed into an 8-wide BVH (`Node8`, 256
//! bytes: SoA child boxes + child references) whose leaves are one or two
//! consecutive packets of up to four triangles in SoA Möller–Trumbore form
//! (`Tri4`, v0/e1/e2). The collapse is SAH-driven (the dynamic programme of
//! Ylitie, Karras & Laine 2017): which BVH2 nodes become 8-wide nodes, which
//! become leaves (a BVH2 subtree of up to eight triangles may become one
//! leaf) and how a node's eight child slots are shared out are chosen for the
//! least SAH cost, which fills the nodes (about 7.3 children on average on a
//! 1M-triangle mesh, against 4.1 for opening the largest child greedily).
//!
//! Traversal: one ray at a time, the 8 boxes of a node per slab test (one
//! AVX2 test, or two 4-wide glam `Vec4` ones: SSE2 on x86-64, NEON on
//! aarch64) and 4 triangles per SIMD triangle test (a leaf's two packets in one
//! AVX2 test: room 1.015x, Cornell box 1.012x, 2026-12-05 (b4ac6ed)), no
//! heap allocation, a fixed-size uninitialised stack sized from the tree at
//! build time, and children visited nearest-first for closest-hit queries.
//! The slab test reads each axis' near and far planes by the ray's octant
//! (Williams et al. 2005), so it needs no per-axis min/max.
//!
//! On large trees traversal waits on memory: the children a node query will
//! visit later are prefetched when they are pushed, and on Linux the node and
//! triangle arrays are copied onto transparent huge pages (`madvise`): fewer pages
//! to translate (random rays on a 1M-triangle height field 1.00-1.12x as fast, 2026-12-04 (4a6faaf);
//! this VM's `perf` has no TLB counters to show the misses themselves).
//!
//! Run-time dispatch ([`Isa`]): the same traversal code is compiled twice, for
//! baseline x86-64 (SSE2) and with AVX2 + FMA enabled (`#[target_feature]`),
//! and each BVH picks the best the CPU has when it is built, so one binary (the
//! Python wheel, a render shard) runs at the speed of the machine it lands on.
//! Rust never contracts `a * b + c` into an FMA on its own, so both versions do
//! the same IEEE operations and return bit-identical hits (tested).
//!
//! Queries are double-sided and report hits with `t` strictly inside
//! `(0, t_max)`, in units of the (not necessarily normalised) ray direction.
//! Degenerate (zero-area or non-finite) triangles are dropped at build time and
//! are never hit.
//!
//! Like Embree's, the slab test maps a zero direction component to a huge
//! reciprocal. A ray with such a component whose origin lies *exactly* in a
//! face plane of a node's box (for that axis) may therefore miss triangle edges
//! or vertices lying on that face; interiors are never missed.

mod build;
mod collapse;
mod instance;
mod leaf;
mod node;
mod sdf;
mod traversal;

use crate::math::{Bounds3, Ray, Vec3};
use collapse::*;
use glam::{Vec3A, Vec4};
use leaf::*;
use node::*;
use rayon::prelude::*;
use traversal::*;

pub use instance::{transformed_bounds, Instances};
pub use sdf::{SdfGrid, SdfShapes, SDF_FIRST_PRIM};

/// Instruction set a BVH's queries run with (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Isa {
    /// Baseline of the target (SSE2 on x86-64, NEON on aarch64).
    Base,
    /// AVX2 + FMA (x86-64 only; chosen when the CPU has both).
    Avx2,
}

impl Isa {
    /// Short name, as printed by `kalos info` and in render statistics.
    pub fn name(self) -> &'static str {
        match self {
            Isa::Base if cfg!(target_arch = "x86_64") => "sse2",
            Isa::Base => "base",
            Isa::Avx2 => "avx2",
        }
    }

    /// Whether this CPU can run `self`.
    pub fn is_available(self) -> bool {
        match self {
            Isa::Base => true,
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2 => is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma"),
            #[cfg(not(target_arch = "x86_64"))]
            Isa::Avx2 => false,
        }
    }

    /// Every instruction set this CPU can run, baseline first.
    pub fn available() -> Vec<Isa> {
        [Isa::Base, Isa::Avx2]
            .into_iter()
            .filter(|i| i.is_available())
            .collect()
    }

    /// The one new BVHs use: the best this CPU has, unless the environment
    /// variable `KALOS_SIMD` names another available one (`sse2`/`base`, `avx2`;
    /// for benchmarks). Decided once per process.
    pub fn chosen() -> Isa {
        static CHOSEN: std::sync::OnceLock<Isa> = std::sync::OnceLock::new();
        *CHOSEN.get_or_init(|| {
            let best = *Isa::available()
                .last()
                .expect("baseline is always available");
            match std::env::var("KALOS_SIMD") {
                Err(_) => best,
                Ok(v) => match Isa::from_name(&v) {
                    Some(i) if i.is_available() => i,
                    _ => {
                        eprintln!(
                            "kalos: warning: KALOS_SIMD={v:?} is not one of this CPU's \
                             instruction sets ({}); using {}",
                            Isa::available()
                                .iter()
                                .map(|i| i.name())
                                .collect::<Vec<_>>()
                                .join(", "),
                            best.name()
                        );
                        best
                    }
                },
            }
        })
    }

    fn from_name(s: &str) -> Option<Isa> {
        match s.trim().to_ascii_lowercase().as_str() {
            "sse2" | "base" | "neon" => Some(Isa::Base),
            "avx2" => Some(Isa::Avx2),
            _ => None,
        }
    }
}

/// Closest-hit record.
#[derive(Clone, Copy, Debug)]
pub struct Hit {
    /// Ray parameter of the hit, in units of `ray.d`.
    pub t: f32,
    /// Index of the triangle in the slice given to [`Bvh::build`].
    pub prim: u32,
    /// Barycentric coordinate of `v1`.
    pub b1: f32,
    /// Barycentric coordinate of `v2`.
    pub b2: f32,
    /// The hit point v0 + b1 e1 + b2 e2 (e1 = v1 - v0, e2 = v2 - v0), and the
    /// geometric normal e1 × e2 (not normalised), from the BVH's own copy of the
    /// triangle: the hit record then reads nothing more of the triangle, whose
    /// packet the traversal has just loaded (on large meshes the scene's own
    /// vertex arrays are another cache and TLB miss per hit).
    pub p: Vec3,
    pub n: Vec3,
}

/// Bounding volume hierarchy over a triangle soup.
#[derive(Clone, Debug)]
pub struct Bvh {
    nodes: Vec<Node8>,
    /// Reference to the root (a `Node8` index or a leaf); unused if empty.
    root: u32,
    bounds: Bounds3,
    /// Traversal stack entries a query may need (computed at build time).
    stack_needed: usize,
    leaf_count: usize,
    /// Triangle packets (one or two per leaf), in traversal order.
    tris: Vec<Tri4>,
    /// Instruction set the queries run with.
    isa: Isa,
    /// [`Bvh::interleaves`] forced (tests, benchmarks); `None`: by size.
    interleave: Option<bool>,
}

/// One query of [`Bvh::trace`]: a ray and its `t_max`.
#[derive(Clone, Copy, Debug)]
pub enum RayQuery {
    /// The closest hit, as [`Bvh::intersect`].
    Closest(Ray, f32),
    /// Whether anything is hit, as [`Bvh::occluded`].
    Occluded(Ray, f32),
}

/// The answer to a [`RayQuery`].
#[derive(Clone, Copy, Debug)]
pub enum RayAnswer {
    Closest(Option<Hit>),
    Occluded(bool),
}

/// Queries [`Bvh::trace`] keeps in flight at once. On the 1M-triangle room at two
/// threads (2026-12-03, c7f9453, after the hit record moved to the BVH's packets), 64 against 32:
/// 1.079x, every round above 1.05; 96: 1.02x (noise); 128: 0.94x.
pub const BATCH: usize = 64;

/// Trees larger than this answer [`Bvh::trace`]'s queries faster with their steps
/// interleaved ([`Bvh::interleaves`]).
pub const BATCH_MIN_BYTES: usize = 8 << 20;

impl Bvh {
    /// Builds the BVH with binned SAH (parallel with rayon on large inputs),
    /// then collapses it into an 8-wide BVH.
    pub fn build(tris: &[[Vec3; 3]]) -> Bvh {
        let (mut refs, mut ids): (Vec<build::PrimRef>, Vec<u32>) = tris
            .par_iter()
            .with_min_len(4096)
            .enumerate()
            .filter_map(|(i, t)| {
                if Tri::new(t).is_degenerate() {
                    return None;
                }
                let [a, b, c] = t.map(Vec3A::from);
                let r = build::PrimRef {
                    min: a.min(b).min(c),
                    max: a.max(b).max(c),
                };
                Some((r, i as u32))
            })
            .unzip();
        if refs.is_empty() {
            return Bvh {
                nodes: Vec::new(),
                root: 0,
                bounds: Bounds3::EMPTY,
                stack_needed: 0,
                leaf_count: 0,
                tris: Vec::new(),
                isa: Isa::chosen(),
                interleave: None,
            };
        }
        assert!(refs.len() < 1 << 28, "too many triangles for one BVH");
        let nodes2 = build::build(&mut refs, &mut ids);
        drop(refs);
        let bounds = Bounds3 {
            min: nodes2[0].min,
            max: nodes2[0].max,
        };
        let plan = plan(&nodes2);
        let mut c = Collapse {
            n2: &nodes2,
            plan: &plan,
            ids: &ids,
            input: tris,
            nodes: Vec::with_capacity(nodes2.len() / 4 + 1),
            packets: Vec::with_capacity(nodes2.len() / 2 + 1),
            leaves: 0,
        };
        let (root, stack_needed) = c.slot(0);
        let Collapse {
            nodes,
            packets,
            leaves,
            ..
        } = c;
        drop(plan);
        // Every 8-wide node spans at least one BVH2 level on every path and
        // the BVH2 depth is bounded by the builder, so this always holds.
        assert!(stack_needed <= LARGE_STACK);
        let (nodes, packets) = (on_huge_pages(nodes), on_huge_pages(packets));
        Bvh {
            nodes,
            root,
            bounds,
            stack_needed,
            leaf_count: leaves,
            tris: packets,
            isa: Isa::chosen(),
            interleave: None,
        }
    }

    /// Whether [`Bvh::trace`] interleaves its queries' traversal steps rather than
    /// answering them one after another: when the tree is larger than
    /// [`BATCH_MIN_BYTES`], so that queries wait on memory (interleaving costs a fifth of
    /// the speed of a tree that sits in the caches).
    pub fn interleaves(&self) -> bool {
        self.interleave
            .unwrap_or(self.memory_bytes() > BATCH_MIN_BYTES)
    }

    /// Forces [`Bvh::interleaves`] (`None`: decided by the tree's size again), for
    /// tests and benchmarks that compare the two ways of answering queries.
    pub fn set_interleaving(&mut self, interleave: Option<bool>) {
        self.interleave = interleave;
    }

    /// Instruction set the queries run with.
    pub fn isa(&self) -> Isa {
        self.isa
    }

    /// Run the queries with `isa` instead (for tests and benchmarks that compare the
    /// paths). Returns false, changing nothing, if this CPU cannot run it.
    pub fn set_isa(&mut self, isa: Isa) -> bool {
        if isa.is_available() {
            self.isa = isa;
        }
        isa.is_available()
    }

    /// Bounds of all non-degenerate triangles (empty for an empty BVH).
    pub fn bounds(&self) -> Bounds3 {
        self.bounds
    }

    /// Shape of the tree: (8-wide nodes, leaves, triangle packets). The
    /// nodes hold `nodes - 1 + leaves` children.
    pub fn shape(&self) -> (usize, usize, usize) {
        (self.nodes.len(), self.leaf_count, self.tris.len())
    }

    /// Number of nodes: 8-wide interior nodes plus leaves (leaves are stored
    /// inline in their parents' child references, so only the former take
    /// node memory).
    pub fn node_count(&self) -> usize {
        self.nodes.len() + self.leaf_count
    }

    /// Heap plus inline memory used by the structure, in bytes.
    pub fn memory_bytes(&self) -> usize {
        std::mem::size_of::<Self>()
            + self.nodes.capacity() * std::mem::size_of::<Node8>()
            + self.tris.capacity() * std::mem::size_of::<Tri4>()
    }
}

/// Asks the CPU to start loading the cache line at `p` into all cache levels (a hint:
/// no effect off x86-64).
#[inline(always)]
pub fn prefetch_line<T>(p: *const T) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: SSE is part of x86-64, and a prefetch never faults whatever the address.
    unsafe {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        _mm_prefetch::<_MM_HINT_T0>(p as *const i8)
    };
    #[cfg(not(target_arch = "x86_64"))]
    let _ = p;
}

/// `v` copied into a new allocation of its exact size whose whole 2 MiB pages Linux is
/// asked to back with transparent huge pages (arrays of 4 MiB or more; smaller ones are
/// returned as they are), for fewer page translations in the traversal of large trees.
///
/// The hint must come before the pages are first touched: memory that is already
/// mapped keeps its 4 KiB pages. The allocator may hand out such memory (glibc's
/// per-thread arenas reuse what the build freed: the work of 2026-12-04 (4a6faaf) found the old hint, given to
/// the build's own vectors, never took effect), so the new allocation's pages are
/// also released (`MADV_DONTNEED`) before the copy writes them, and the copy's first
/// touch then maps huge pages. A hint only: failures are ignored.
fn on_huge_pages<T: Copy>(mut v: Vec<T>) -> Vec<T> {
    #[cfg(target_os = "linux")]
    {
        const HUGE: usize = 2 << 20;
        let bytes = std::mem::size_of_val(v.as_slice());
        if bytes < 2 * HUGE {
            v.shrink_to_fit();
            return v;
        }
        let mut out: Vec<T> = Vec::with_capacity(v.len());
        let start = out.as_ptr() as usize;
        let (a, b) = (start.next_multiple_of(HUGE), (start + bytes) / HUGE * HUGE);
        if b > a {
            // SAFETY: both calls only change how the kernel backs pages inside `out`'s
            // own allocation, none of which has been written yet (its length is 0):
            // MADV_DONTNEED drops whatever the allocator left there (reads would see
            // zeros; nothing reads them before the copy below writes them).
            unsafe {
                libc::madvise(a as *mut libc::c_void, b - a, libc::MADV_HUGEPAGE);
                libc::madvise(a as *mut libc::c_void, b - a, libc::MADV_DONTNEED);
            }
        }
        out.extend_from_slice(&v);
        out
    }
    #[cfg(not(target_os = "linux"))]
    {
        v.shrink_to_fit();
        v
    }
}

#[cfg(test)]
mod tests;
