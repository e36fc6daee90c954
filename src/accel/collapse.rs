//! The SAH-driven collapse of the BVH2 into the 8-wide tree (Ylitie, Karras and Laine
//! 2017): which nodes become 8-wide nodes and which become leaves, by dynamic programming.

use super::*;

/// SAH cost of visiting an 8-wide node, relative to testing one triangle
/// packet (both per unit of half area), for the collapse's dynamic programme.
/// A node is four cache lines and a packet three, and a node also sorts the
/// children it pushes. Render A/Bs on a shared machine (noise of several
/// percent; docs/results/throughput/bvh-bench-fill.txt): 1.5 and 2 alike, 1
/// and 3 no better on the 1M-triangle mesh; 3 (one node of 8 children, two
/// two-packet leaves) made the Cornell box 2% slower.
pub(super) const C_NODE: f32 = 2.0;

/// Per BVH2 node, the least SAH cost of its subtree as at most `j + 1` child
/// slots of an 8-wide node (`cost[j]`, each slot a leaf or an 8-wide node),
/// and its triangle count. Costs are in units of one packet test over the
/// box's half area: a leaf of `n` triangles costs `ceil(n / 4)` times its
/// half area, an 8-wide node `C_NODE` times its half area plus its children.
#[derive(Clone, Copy)]
pub(super) struct Plan {
    pub(super) cost: [f32; WIDTH],
    pub(super) tris: u32,
    /// Whether the subtree as one slot is best a leaf.
    pub(super) leaf: bool,
}

/// Half area of a BVH2 node's box.
#[inline(always)]
pub(super) fn area2(n: &Node) -> f32 {
    Bounds3 {
        min: n.min,
        max: n.max,
    }
    .half_area()
}

/// The best split of `j` slots (2 <= j <= 8) between the two children of an
/// interior BVH2 node: (slots of the left child, cost); the first on ties.
#[inline(always)]
pub(super) fn best_split(plan: &[Plan], left: usize, j: usize) -> (usize, f32) {
    let (l, r) = (&plan[left].cost, &plan[left + 1].cost);
    let mut best = (1, l[0] + r[j - 2]);
    for k in 2..j {
        let c = l[k - 1] + r[j - k - 1];
        if c < best.1 {
            best = (k, c);
        }
    }
    best
}

/// The dynamic programme of Ylitie, Karras & Laine (2017, "Efficient
/// incoherent ray traversal on GPUs through compressed wide BVHs"), bottom-up
/// over the BVH2 (children always follow their parent in `n2`).
pub(super) fn plan(n2: &[Node]) -> Vec<Plan> {
    let mut plan = vec![
        Plan {
            cost: [0.0; WIDTH],
            tris: 0,
            leaf: false,
        };
        n2.len()
    ];
    for i in (0..n2.len()).rev() {
        let n = &n2[i];
        let a = area2(n);
        let tris = if n.is_leaf() {
            n.count
        } else {
            plan[n.a as usize].tris + plan[n.a as usize + 1].tris
        };
        let leaf = if tris <= MAX_LEAF_TRIS {
            a * tris.div_ceil(4) as f32
        } else {
            f32::INFINITY
        };
        let mut cost = [leaf; WIDTH];
        let mut is_leaf = true;
        if !n.is_leaf() {
            let node = a * C_NODE + best_split(&plan, n.a as usize, WIDTH).1;
            // (Infinite or NaN areas must not make a leaf of too many triangles.)
            is_leaf = tris <= MAX_LEAF_TRIS && leaf <= node;
            cost[0] = leaf.min(node);
            for j in 2..=WIDTH {
                cost[j - 1] = cost[0].min(best_split(&plan, n.a as usize, j).1);
            }
        }
        plan[i] = Plan {
            cost,
            tris,
            leaf: is_leaf,
        };
    }
    plan
}

/// BVH2 → 8-wide BVH conversion state.
pub(super) struct Collapse<'a> {
    pub(super) n2: &'a [Node],
    pub(super) plan: &'a [Plan],
    /// Input triangle indices in BVH2 leaf order.
    pub(super) ids: &'a [u32],
    pub(super) input: &'a [[Vec3; 3]],
    pub(super) nodes: Vec<Node8>,
    pub(super) packets: Vec<Tri4>,
    pub(super) leaves: usize,
}

impl Collapse<'_> {
    /// Appends to `out` the BVH2 nodes that, as at most `j` child slots, cover
    /// the subtree at `i` at least cost.
    pub(super) fn distribute(&self, i: usize, j: usize, out: &mut Vec<usize>) {
        let n = &self.n2[i];
        let p = &self.plan[i];
        if j == 1 || n.is_leaf() || p.cost[j - 1] == p.cost[0] {
            out.push(i);
            return;
        }
        let (k, _) = best_split(self.plan, n.a as usize, j);
        self.distribute(n.a as usize, k, out);
        self.distribute(n.a as usize + 1, j - k, out);
    }

    /// Turns the BVH2 subtree at `i` into one child slot: a leaf of its
    /// triangles or an 8-wide node, whichever the plan found cheaper; nodes
    /// and packets are laid out depth-first. Returns its reference and the
    /// number of traversal stack entries a query below it may need.
    pub(super) fn slot(&mut self, i: usize) -> (u32, usize) {
        let n2 = self.n2;
        let n = &n2[i];
        let p = self.plan[i];
        if p.leaf {
            // The subtree's triangles are contiguous in leaf order.
            let mut first = i;
            while !n2[first].is_leaf() {
                first = n2[first].a as usize;
            }
            let first = n2[first].a as usize;
            let ids = &self.ids[first..first + p.tris as usize];
            let r = leaf_ref(self.packets.len() as u32, p.tris);
            for chunk in ids.chunks(4) {
                let mut tris = [Tri::new(&[Vec3::ZERO; 3]); 4];
                for (t, &i) in tris.iter_mut().zip(chunk) {
                    *t = Tri::new(&self.input[i as usize]);
                }
                self.packets.push(Tri4::new(&tris[..chunk.len()], chunk));
            }
            self.leaves += 1;
            return (r, 0);
        }
        let mut kids = Vec::with_capacity(WIDTH);
        let (k, _) = best_split(self.plan, n.a as usize, WIDTH);
        self.distribute(n.a as usize, k, &mut kids);
        self.distribute(n.a as usize + 1, WIDTH - k, &mut kids);
        debug_assert!((2..=WIDTH).contains(&kids.len()));
        let idx = self.nodes.len();
        // Unused lanes get the box [+inf, +inf], which no ray overlaps.
        let mut b = [[f32::INFINITY; WIDTH]; 6];
        for (lane, &k) in kids.iter().enumerate() {
            for a in 0..3 {
                b[a][lane] = n2[k].min[a];
                b[a + 3][lane] = n2[k].max[a];
            }
        }
        self.nodes.push(Node8 {
            b,
            child: [0; WIDTH],
        });
        let mut stack_needed = 0;
        for (lane, &k) in kids.iter().enumerate() {
            let (r, s) = self.slot(k);
            self.nodes[idx].child[lane] = r;
            stack_needed = stack_needed.max(s);
        }
        (idx as u32, stack_needed + kids.len() - 1)
    }
}
