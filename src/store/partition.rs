//! The pilot k-d partition that assigns photons to tiles.
//!
//! Photons crowd toward the sea surface and onto the floor, so a uniform grid
//! makes a few huge tiles and many empty ones. A pilot sample of positions is
//! split at quantiles along the longest axis of each cell until there is one
//! cell per intended tile; every photon is then routed by the split planes.
//! The partition is approximate by design: a cell that still overflows is
//! split again when the map is finished (see `writer`).

use super::format::PartitionNode;
use crate::bounds::Aabb;
use glam::Vec3;

/// A k-d partition of space into cells (tiles), stored in preorder.
#[derive(Clone, Debug, PartialEq)]
pub struct Partition {
    nodes: Vec<PartitionNode>,
    /// For a split node, the index of its right child; for a leaf, its cell number.
    link: Vec<u32>,
    cells: u32,
    /// The nodes as [`Partition::cells_of`] walks them.
    steps: Vec<Step>,
    /// Splits on the longest path from the root to a leaf.
    depth: usize,
}

/// A node for descents in lockstep: go to the next node where
/// `p[axis] < value`, else to `right`. A leaf has the value -inf, which
/// nothing is below, and points right at itself, so a descent that reached
/// it stays.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Step {
    value: f32,
    axis: u32,
    right: u32,
}

/// Points [`Partition::cells_of`] descends with at once.
const LANES: usize = 16;

impl Partition {
    /// Split the pilot `points` into (at most) `cells` cells of nearly equal counts.
    pub fn from_pilot(points: &mut [Vec3], cells: usize) -> Partition {
        let mut nodes = Vec::new();
        build(points, cells.max(1), &mut nodes);
        Partition::from_nodes(nodes).expect("a built partition is well formed")
    }

    /// One cell holding everything.
    pub fn single() -> Partition {
        Partition::from_nodes(vec![PartitionNode::Leaf]).unwrap()
    }

    /// Rebuild from a preorder node list (as stored in a map header); `None`
    /// when the list is not exactly one well-formed tree.
    pub fn from_nodes(nodes: Vec<PartitionNode>) -> Option<Partition> {
        let mut link = vec![0u32; nodes.len()];
        let mut cells = 0u32;
        // Iterative preorder walk: returns the index just past each subtree.
        fn walk(
            nodes: &[PartitionNode],
            link: &mut [u32],
            cells: &mut u32,
            i: usize,
            depth: usize,
        ) -> Option<usize> {
            if depth > 64 {
                return None;
            }
            match nodes.get(i)? {
                PartitionNode::Leaf => {
                    link[i] = *cells;
                    *cells += 1;
                    Some(i + 1)
                }
                PartitionNode::Split { axis, value } => {
                    if *axis > 2 || !value.is_finite() {
                        return None;
                    }
                    let right = walk(nodes, link, cells, i + 1, depth + 1)?;
                    link[i] = right as u32;
                    walk(nodes, link, cells, right, depth + 1)
                }
            }
        }
        let end = walk(&nodes, &mut link, &mut cells, 0, 0)?;
        if end != nodes.len() {
            return None;
        }
        let mut depth = 0;
        let mut at_depth = vec![0usize; nodes.len()];
        let steps = nodes
            .iter()
            .enumerate()
            .map(|(i, node)| match *node {
                PartitionNode::Split { axis, value } => {
                    at_depth[i + 1] = at_depth[i] + 1;
                    at_depth[link[i] as usize] = at_depth[i] + 1;
                    Step {
                        value,
                        axis: axis as u32,
                        right: link[i],
                    }
                }
                PartitionNode::Leaf => {
                    depth = depth.max(at_depth[i]);
                    Step {
                        value: f32::NEG_INFINITY,
                        axis: 0,
                        right: i as u32,
                    }
                }
            })
            .collect();
        Some(Partition {
            nodes,
            link,
            cells,
            steps,
            depth,
        })
    }

    /// The preorder node list (for the map header).
    pub fn nodes(&self) -> &[PartitionNode] {
        &self.nodes
    }

    /// Number of cells.
    pub fn cells(&self) -> u32 {
        self.cells
    }

    /// The cells holding `points`, into `out` (as long): what
    /// [`Partition::cell_of`] gives, found for [`LANES`] points at a time
    /// in lockstep, one level per step, without branches. A single descent
    /// is a chain of dependent loads and unpredictable branches, a dozen or
    /// more deep in a partition of 10^3 to 10^5 cells (80-110 ns a point at
    /// 18 500 cells on the test machine); the descents of different points
    /// are independent, so in lockstep their loads overlap.
    pub fn cells_of(&self, points: &[Vec3], out: &mut [u32]) {
        assert_eq!(points.len(), out.len());
        for (points, out) in points.chunks(LANES).zip(out.chunks_mut(LANES)) {
            let mut at = [0u32; LANES];
            let at = &mut at[..points.len()];
            let mut coords = [[0f32; 3]; LANES];
            for (c, p) in coords.iter_mut().zip(points) {
                *c = p.to_array();
            }
            for _ in 0..self.depth {
                for (i, c) in at.iter_mut().zip(&coords) {
                    let step = self.steps[*i as usize];
                    // Not an `if`, which compiles to a branch that
                    // mispredicts half the time (so does a mask: LLVM sees
                    // the select in it). A NaN coordinate goes right.
                    let left = c[(step.axis as usize).min(2)] < step.value;
                    *i = std::hint::select_unpredictable(left, *i + 1, step.right);
                }
            }
            for (cell, &i) in out.iter_mut().zip(at.iter()) {
                *cell = self.link[i as usize];
            }
        }
    }

    /// The cell holding `p`.
    #[inline]
    pub fn cell_of(&self, p: Vec3) -> u32 {
        let mut i = 0;
        loop {
            match self.nodes[i] {
                PartitionNode::Leaf => return self.link[i],
                PartitionNode::Split { axis, value } => {
                    i = if p[axis as usize] < value {
                        i + 1
                    } else {
                        self.link[i] as usize
                    };
                }
            }
        }
    }
}

fn build(points: &mut [Vec3], cells: usize, nodes: &mut Vec<PartitionNode>) {
    if cells <= 1 || points.len() < 2 {
        nodes.push(PartitionNode::Leaf);
        return;
    }
    let mut b = Aabb::EMPTY;
    for &p in points.iter() {
        b.grow(p);
    }
    let axis = b.longest_axis();
    if b.max[axis] <= b.min[axis] {
        nodes.push(PartitionNode::Leaf);
        return;
    }
    let left_cells = cells / 2;
    let k = (points.len() * left_cells / cells).clamp(1, points.len() - 1);
    points.select_nth_unstable_by(k, |a, b| a[axis].total_cmp(&b[axis]));
    let mut value = points[k][axis];
    if value <= b.min[axis] {
        // Many pilot points share the minimum (a flat floor): cut just above it.
        value = next_up(b.min[axis]);
    }
    let mid = partition_in_place(points, |p| p[axis] < value);
    nodes.push(PartitionNode::Split {
        axis: axis as u8,
        value,
    });
    let (left, right) = points.split_at_mut(mid);
    build(left, left_cells, nodes);
    build(right, cells - left_cells, nodes);
}

fn next_up(x: f32) -> f32 {
    if x.is_nan() || x == f32::INFINITY {
        return x;
    }
    let bits = x.to_bits();
    let next = if x == 0.0 {
        1
    } else if x > 0.0 {
        bits + 1
    } else {
        bits - 1
    };
    f32::from_bits(next)
}

/// Moves the elements for which `pred` holds to the front; returns their count.
fn partition_in_place(v: &mut [Vec3], pred: impl Fn(&Vec3) -> bool) -> usize {
    let mut i = 0;
    for j in 0..v.len() {
        if pred(&v[j]) {
            v.swap(i, j);
            i += 1;
        }
    }
    i
}

#[cfg(test)]
mod tests;
