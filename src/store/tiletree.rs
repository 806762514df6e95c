//! A k-d tree over a tile's photons that builds at decode speed, and the
//! bounded buffer of a k-nearest search ([`Nearest`]).
//!
//! A tile stores its photons sorted by the Morton code of their 16-bit
//! positions in the tile's box (`store::codec`). That order is already a
//! k-d tree: the photons sharing a code prefix are contiguous and fill one
//! octree cell. [`TileTree::from_morton`] cuts the sorted run at the
//! highest bit in which its first and last codes differ (a binary radix
//! tree, as in Karras 2012), down to leaves of at most [`LEAF`] photons.
//! Each cut is a plane on the axis that bit encodes, at the first cell of
//! the upper half, so a node is 16 bytes (plane, axis, second child and
//! its first item, from which a query prefetches that side's cells) and
//! the build needs no sort, no median search and no pass over the
//! positions: one binary search per node. A cache miss costs the decode
//! and little more. Nothing beyond the codes is stored, so the map format
//! is unchanged and maps written before read as they are.
//!
//! The tree keeps the photons' 16-bit cells (6 bytes a photon) and scans
//! those rather than the 24-byte records. A leaf's cells are stored axis by
//! axis (its x cells, then its y cells, then its z cells), so a leaf's
//! distances are computed [`LEAF`] lanes at a time in SIMD registers, as
//! the same f32 operations a photon's own distance takes; lanes past the
//! leaf read the next leaf's cells (or the padding at the end) and are
//! ignored. A query walks the tree depth first,
//! nearer side first, keeping the distance to each side's cell per axis,
//! and prunes a side whose cell lies beyond the current bound. The cell
//! distance and the photon distance are computed with the same f32
//! operations from quantities ordered the same way, so a cell is never
//! farther than a photon in it and pruning is exact.
//!
//! Not for: the hierarchy over the map's tile boxes (`store::boxtree`),
//! paging tiles (`store::cache`) or assembling a query's results
//! (`store::query`).

use crate::bounds::Aabb;
use crate::photon::PackedPhoton;
use crate::simd::prefetch;
use crate::store::codec::BoxQuantizer;

/// Most photons in a leaf of a tile's tree.
pub const LEAF: usize = 16;

/// Deepest tree: 48 radix levels (one per Morton bit) and 32 count
/// splits of runs of equal codes; the traversal stack holds one entry per
/// level.
const MAX_DEPTH: usize = 96;

#[cfg(test)]
fn point_distance_sq(p: &[f32; 3], q: &[f32; 3]) -> f32 {
    let (dx, dy, dz) = (p[0] - q[0], p[1] - q[1], p[2] - q[2]);
    dx * dx + dy * dy + dz * dz
}

#[inline(always)]
fn norm_sq(o: &[f32; 3]) -> f32 {
    o[0] * o[0] + o[1] * o[1] + o[2] * o[2]
}

// ---------------------------------------------------------------- tiles

/// A node of a tile's tree, in pre-order. A leaf (`count > 0`) holds
/// items `link..link + count`. An internal node's first child follows it
/// and holds the photons below `split` on `axis`; its second child, at
/// `link`, those at or above it, from item `mid` on.
#[derive(Clone, Copy, Debug)]
#[repr(C)]
struct KdNode {
    split: f32,
    link: u32,
    mid: u32,
    axis: u8,
    count: u8,
}

const _: () = assert!(std::mem::size_of::<KdNode>() == 16);

/// One side of an internal node: its node and its first item.
#[derive(Clone, Copy)]
struct Side {
    node: usize,
    first: usize,
}

impl KdNode {
    /// For this internal node at index `node`, whose items start at
    /// `first`: the side holding `q`, the other side, and the per-axis
    /// distance from `q` to the other side's cell, given `offset`, the
    /// distance to this node's cell.
    #[inline(always)]
    fn sides(
        &self,
        node: usize,
        first: usize,
        q: &[f32; 3],
        offset: &[f32; 3],
    ) -> (Side, Side, [f32; 3]) {
        let a = self.axis as usize;
        let diff = q[a] - self.split;
        let lower = Side {
            node: node + 1,
            first,
        };
        let upper = Side {
            node: self.link as usize,
            first: self.mid as usize,
        };
        let (near, far) = if diff < 0.0 {
            (lower, upper)
        } else {
            (upper, lower)
        };
        let mut far_offset = *offset;
        far_offset[a] = diff.abs();
        (near, far, far_offset)
    }
}

/// A tile's search tree (items are the tile's photons in stored order).
#[derive(Clone, Debug)]
pub struct TileTree {
    nodes: Vec<KdNode>,
    /// The photons' 16-bit cells in the tile's box, leaf by leaf: for the
    /// leaf of items `lo..lo + n`, their x cells from `3 lo`, y cells from
    /// `3 lo + n` and z cells from `3 lo + 2 n`; then [`CELL_PAD`] zeros.
    cells: Vec<u16>,
    /// Per axis, the box minimum and the cell size: a cell `c` decodes to
    /// `min + c * step` (`AxisQuantizer::decode`).
    min: [f32; 3],
    step: [f32; 3],
}

/// Zeros after the last leaf's cells, so that every leaf can be read as
/// [`LEAF`] lanes per axis.
const CELL_PAD: usize = 3 * LEAF;

/// A pending item of [`Nearest`]: an index into the tile being searched,
/// not yet copied out of it.
const PENDING: u32 = 1 << 31;

/// The `k` nearest photons found so far, none farther than a limit: a
/// buffer of (squared distance, item) candidates, none farther than the
/// bound, cut back to the `k` nearest (a selection, linear in its length)
/// whenever it reaches [`CUT_AT`] times k and after each tile. Each offer
/// is one comparison and a push: a max-heap of k = 2000 spent about 40 %
/// of a search in the branches of its sift, eleven levels deep. Between cuts
/// the bound is the k-th distance of the last cut, looser than the heap's
/// would be, which costs a few more offers and no correctness. One buffer
/// serves a query across all the tiles it visits; the records of the
/// photons taken from a tile are copied out of it once the tile is
/// searched ([`Nearest::take_records`]), so photons that enter the buffer
/// and leave it again are never read.
#[derive(Default)]
pub struct Nearest {
    k: usize,
    bound: f32,
    found: Vec<(f32, u32)>,
    records: Vec<PackedPhoton>,
}

/// The buffer of [`Nearest`] is cut back to k when it holds this many
/// times k candidates.
const CUT_AT: usize = 2;

impl Nearest {
    /// Empty, for the `k` nearest (k > 0) within `limit_sq`.
    pub fn reset(&mut self, k: usize, limit_sq: f32) {
        assert!(k > 0, "k nearest with k = 0");
        self.k = k;
        self.bound = limit_sq;
        self.found.clear();
        self.records.clear();
    }

    /// Squared distance beyond which nothing more can be taken.
    #[inline(always)]
    pub fn bound_sq(&self) -> f32 {
        self.bound
    }

    #[inline(always)]
    fn offer(&mut self, d: f32, item: u32) {
        if d <= self.bound {
            self.found.push((d, item | PENDING));
            if self.found.len() >= CUT_AT * self.k {
                self.cut();
            }
        }
    }

    /// Keep the k nearest candidates (any of equal distances at the k-th)
    /// and bound what follows by the k-th distance.
    fn cut(&mut self) {
        let k = self.k;
        if self.found.len() > k {
            // The k-th lands at k - 1, with none farther before it.
            self.found
                .select_nth_unstable_by(k - 1, |a, b| a.0.total_cmp(&b.0));
            self.found.truncate(k);
            self.bound = self.found[k - 1].0;
        } else if self.found.len() == k {
            self.bound = self.found.iter().fold(0.0f32, |m, e| m.max(e.0));
        }
    }

    /// Cut back to the k nearest, then copy the records of the photons
    /// taken from the tile just searched (whose photons are `photons`).
    fn take_records(&mut self, photons: &[PackedPhoton]) {
        self.cut();
        for e in &mut self.found {
            if e.1 & PENDING != 0 {
                self.records.push(photons[(e.1 & !PENDING) as usize]);
                e.1 = (self.records.len() - 1) as u32;
            }
        }
    }

    /// The photons found (after [`Nearest::take_records`]), nearest first
    /// when `sorted`, else in the buffer's order.
    pub fn results(&mut self, sorted: bool) -> impl Iterator<Item = (f32, &PackedPhoton)> {
        if sorted {
            self.found.sort_by(|a, b| a.0.total_cmp(&b.0));
        }
        let records = &self.records;
        self.found.iter().map(move |&(d, r)| {
            debug_assert!(r & PENDING == 0, "records not taken");
            (d, &records[r as usize])
        })
    }
}

/// Restore the order of the heap `h` after a push: the last entry moves
/// up past every parent that `above` puts below it (a hole moves instead
/// of swaps; the heap is the one swaps would give). `above(a, b)`: `a`
/// belongs nearer the top than `b`.
#[inline(always)]
pub(crate) fn sift_up<T: Copy>(h: &mut [T], above: impl Fn(T, T) -> bool) {
    let mut i = h.len() - 1;
    let v = h[i];
    while i > 0 {
        let parent = (i - 1) / 2;
        if !above(v, h[parent]) {
            break;
        }
        h[i] = h[parent];
        i = parent;
    }
    h[i] = v;
}

/// Put `v` at the top of the heap `h` and move it down to its place: the
/// hole moves down past every child that `above` puts above `v`, taking
/// the child of two that it puts above the other without a branch.
/// `above(a, b)`: `a` belongs nearer the top than `b`.
#[inline(always)]
pub(crate) fn sift_down<T: Copy>(h: &mut [T], v: T, above: impl Fn(T, T) -> bool) {
    let n = h.len();
    let mut i = 0;
    loop {
        let l = 2 * i + 1;
        if l >= n {
            break;
        }
        let r = l + 1;
        let c = if r < n {
            l + above(h[r], h[l]) as usize
        } else {
            l
        };
        if !above(h[c], v) {
            break;
        }
        h[i] = h[c];
        i = c;
    }
    h[i] = v;
}

/// The traversal state of one side not yet visited.
#[derive(Clone, Copy)]
struct Pending {
    /// Distance from the query to the side's cell, per axis.
    offset: [f32; 3],
    distance_sq: f32,
    node: u32,
    /// The side's first item.
    first: u32,
}

impl TileTree {
    /// The tree over a tile's photons given their Morton `codes` (sorted,
    /// the order a tile is stored and decoded in) of 16-bit `cells` (the
    /// codes un-interleaved) in the box `quant`.
    pub fn from_morton(codes: &[u64], cells: &[[u16; 3]], quant: &Aabb) -> TileTree {
        debug_assert!(codes.windows(2).all(|w| w[0] <= w[1]));
        debug_assert_eq!(codes.len(), cells.len());
        let quant = BoxQuantizer::new(quant);
        let mut tree = TileTree {
            nodes: Vec::with_capacity(4 * codes.len().div_ceil(LEAF) + 1),
            cells: vec![0; 3 * codes.len() + CELL_PAD],
            min: [0, 1, 2].map(|a| quant.decode_axis(a, 0)),
            step: [0, 1, 2].map(|a| quant.step(a)),
        };
        if !codes.is_empty() {
            tree.radix(codes, cells, 0, codes.len());
        }
        tree.nodes.shrink_to_fit();
        tree
    }

    /// Bytes of one node.
    pub const NODE_BYTES: u64 = std::mem::size_of::<KdNode>() as u64;

    /// Bytes of padding after the cells.
    pub const PAD_BYTES: u64 = (CELL_PAD * std::mem::size_of::<u16>()) as u64;

    fn decode_axis(&self, axis: usize, c: u16) -> f32 {
        self.min[axis] + c as f32 * self.step[axis]
    }

    fn radix(&mut self, codes: &[u64], cells: &[[u16; 3]], lo: usize, hi: usize) {
        if hi - lo <= LEAF {
            let n = hi - lo;
            for (j, c) in cells[lo..hi].iter().enumerate() {
                for (a, &ca) in c.iter().enumerate() {
                    self.cells[3 * lo + a * n + j] = ca;
                }
            }
            self.nodes.push(KdNode {
                split: 0.0,
                link: lo as u32,
                mid: lo as u32,
                axis: 0,
                count: (hi - lo) as u8,
            });
            return;
        }
        let differ = codes[lo] ^ codes[hi - 1];
        let (mid, axis, split) = if differ == 0 {
            // A run of equal codes: split it by count, at their position.
            let mid = lo + (hi - lo) / 2;
            (mid, 0, self.decode_axis(0, cells[mid][0]))
        } else {
            let bit = 63 - differ.leading_zeros();
            let mid = lo + codes[lo..hi].partition_point(|&c| c & (1 << bit) == 0);
            // Bit `bit` is bit `bit / 3` of axis `bit % 3`: the upper half's
            // cells on that axis start at the first one's with lower bits
            // cleared.
            let (axis, j) = ((bit % 3) as usize, bit / 3);
            let first = (cells[mid][axis] >> j) << j;
            (mid, axis, self.decode_axis(axis, first))
        };
        let at = self.nodes.len();
        self.nodes.push(KdNode {
            split,
            link: 0,
            mid: mid as u32,
            axis: axis as u8,
            count: 0,
        });
        self.radix(codes, cells, lo, mid);
        self.nodes[at].link = self.nodes.len() as u32;
        self.radix(codes, cells, mid, hi);
    }

    /// Bytes this tree holds.
    pub fn heap_bytes(&self) -> usize {
        self.nodes.capacity() * std::mem::size_of::<KdNode>()
            + self.cells.capacity() * std::mem::size_of::<u16>()
    }

    /// Nodes in the tree.
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// True for a tree over nothing.
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// Squared distances from `q` to the photons of the leaf of items
    /// `lo..lo + n` (lane `j` for item `lo + j`, lanes from `n` on
    /// meaningless): each `point_distance_sq(position, q)` of the photon's
    /// cell decoded as the tile's decoder decodes it, bit for bit.
    #[inline(always)]
    fn leaf_distances(&self, lo: usize, n: usize, q: &[f32; 3]) -> [f32; LEAF] {
        let at = |a: usize| -> &[u16; LEAF] {
            let from = 3 * lo + a * n;
            self.cells[from..from + LEAF].try_into().unwrap()
        };
        let (xs, ys, zs) = (at(0), at(1), at(2));
        let mut d = [0.0f32; LEAF];
        for j in 0..LEAF {
            let dx = (self.min[0] + xs[j] as f32 * self.step[0]) - q[0];
            let dy = (self.min[1] + ys[j] as f32 * self.step[1]) - q[1];
            let dz = (self.min[2] + zs[j] as f32 * self.step[2]) - q[2];
            d[j] = dx * dx + dy * dy + dz * dz;
        }
        d
    }

    /// Position of item `i` of the leaf of items `lo..lo + n`.
    #[cfg(test)]
    fn position(&self, lo: usize, n: usize, i: usize) -> [f32; 3] {
        [0, 1, 2].map(|a| self.decode_axis(a, self.cells[3 * lo + a * n + (i - lo)]))
    }

    /// Offer every photon of this tile (whose photons, in stored order,
    /// are `photons`) that could be among the nearest to `q` to `nearest`,
    /// and copy out the records of those it keeps.
    pub fn nearest(&self, photons: &[PackedPhoton], q: &[f32; 3], nearest: &mut Nearest) {
        debug_assert_eq!(photons.len() * 3 + CELL_PAD, self.cells.len());
        self.offer_nearest(photons, q, nearest);
        nearest.take_records(photons);
    }

    fn offer_nearest(&self, photons: &[PackedPhoton], q: &[f32; 3], nearest: &mut Nearest) {
        if self.nodes.is_empty() {
            return;
        }
        let mut stack = [Pending {
            offset: [0.0; 3],
            distance_sq: 0.0,
            node: 0,
            first: 0,
        }; MAX_DEPTH];
        let mut top = 0;
        let (mut node, mut first) = (0usize, 0usize);
        let mut offset = [0.0f32; 3];
        loop {
            let n = self.nodes[node];
            if n.count == 0 {
                let (near, far, far_offset) = n.sides(node, first, q, &offset);
                let far_sq = norm_sq(&far_offset);
                if far_sq <= nearest.bound_sq() {
                    // It is read when popped unless the bound has shrunk
                    // past it by then: its node, and (if it is a leaf) the
                    // cells from its first item.
                    prefetch(&self.nodes[far.node]);
                    prefetch(&self.cells[3 * far.first]);
                    prefetch(&self.cells[3 * far.first + 32]);
                    stack[top] = Pending {
                        offset: far_offset,
                        distance_sq: far_sq,
                        node: far.node as u32,
                        first: far.first as u32,
                    };
                    top += 1;
                }
                (node, first) = (near.node, near.first);
                continue;
            }
            let (lo, count) = (n.link as usize, n.count as usize);
            let d = self.leaf_distances(lo, count, q);
            let mut bound = nearest.bound_sq();
            for (j, &dj) in d[..count].iter().enumerate() {
                if dj <= bound {
                    // Its record is read if it stays: start that load now.
                    prefetch(&photons[lo + j]);
                    nearest.offer(dj, (lo + j) as u32);
                    bound = nearest.bound_sq();
                }
            }
            // The next side still within reach.
            loop {
                if top == 0 {
                    return;
                }
                top -= 1;
                let p = &stack[top];
                if p.distance_sq <= nearest.bound_sq() {
                    (node, first, offset) = (p.node as usize, p.first as usize, p.offset);
                    break;
                }
            }
        }
    }

    /// Append every photon of `photons` (the tile's, in stored order)
    /// within `radius_sq` of `q` to `out`.
    pub fn within(
        &self,
        photons: &[PackedPhoton],
        q: &[f32; 3],
        radius_sq: f32,
        out: &mut Vec<(f32, PackedPhoton)>,
    ) {
        if self.nodes.is_empty() {
            return;
        }
        let mut stack = [([0.0f32; 3], 0u32); MAX_DEPTH];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let (offset, mut node) = (stack[top].0, stack[top].1 as usize);
            loop {
                let n = self.nodes[node];
                if n.count == 0 {
                    let (near, far, far_offset) = n.sides(node, 0, q, &offset);
                    if norm_sq(&far_offset) <= radius_sq {
                        stack[top] = (far_offset, far.node as u32);
                        top += 1;
                    }
                    node = near.node;
                    continue;
                }
                let (lo, count) = (n.link as usize, n.count as usize);
                let d = self.leaf_distances(lo, count, q);
                for (p, &dj) in photons[lo..lo + count].iter().zip(&d) {
                    if dj <= radius_sq {
                        out.push((dj, *p));
                    }
                }
                break;
            }
        }
    }
}

#[cfg(test)]
mod tests;
