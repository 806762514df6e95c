//! A bounding-volume hierarchy over the map's tile boxes:
//! [`BoxTree::over_boxes`] splits a list of boxes at the median along the
//! longest axis of their centres, with both children's boxes in each
//! 64-byte node, for the tile-box index a query walks nearest first.
//!
//! Not for: the search inside a tile (`store::tiletree`).

use crate::bounds::Aabb;
use crate::store::tiletree::{sift_down, sift_up};
use glam::Vec3;

/// A child of a node: another node, or a leaf's run of items.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Child {
    Node(u32),
    Leaf { start: u32, count: u32 },
}

/// An internal node: both children's boxes, so one cache line decides
/// which to visit. A child with `count[i] > 0` is a leaf of `count[i]`
/// items from `child[i]`; `child[i] == NONE` is no child (an empty box,
/// min +inf and max -inf, infinitely far from every point); otherwise
/// `child[i]` is a node.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
struct Node {
    min: [[f32; 3]; 2],
    max: [[f32; 3]; 2],
    child: [u32; 2],
    count: [u32; 2],
}

const _: () = assert!(std::mem::size_of::<Node>() == 64);

/// [`Node::child`] of a missing child.
const NONE: u32 = u32::MAX;

impl Node {
    #[inline(always)]
    fn distance_sq(&self, i: usize, q: &[f32; 3]) -> f32 {
        let mut s = 0.0f32;
        for (a, &qa) in q.iter().enumerate() {
            let d = (self.min[i][a] - qa).max(qa - self.max[i][a]).max(0.0);
            s += d * d;
        }
        s
    }

    #[inline(always)]
    fn child(&self, i: usize) -> Child {
        if self.count[i] > 0 {
            Child::Leaf {
                start: self.child[i],
                count: self.count[i],
            }
        } else if self.child[i] == NONE {
            Child::Leaf { start: 0, count: 0 }
        } else {
            Child::Node(self.child[i])
        }
    }

    fn set(&mut self, i: usize, b: &Aabb, c: Child) {
        self.min[i] = b.min.to_array();
        self.max[i] = b.max.to_array();
        (self.child[i], self.count[i]) = match c {
            Child::Node(n) => (n, 0),
            Child::Leaf { start, count } => (start, count),
        };
    }

    const EMPTY: Node = Node {
        min: [[f32::INFINITY; 3]; 2],
        max: [[f32::NEG_INFINITY; 3]; 2],
        child: [NONE; 2],
        count: [0; 2],
    };
}

/// A bounding-volume hierarchy over boxes, in pre-order.
#[derive(Clone, Debug, Default)]
pub struct BoxTree {
    nodes: Vec<Node>,
}

impl BoxTree {
    /// A tree over `boxes` with one box per leaf (items index `boxes`).
    pub fn over_boxes(boxes: &[Aabb]) -> BoxTree {
        let mut items: Vec<(Vec3, u32)> = boxes
            .iter()
            .enumerate()
            .map(|(i, b)| ((b.min + b.max) * 0.5, i as u32))
            .collect();
        let mut tree = BoxTree {
            nodes: Vec::with_capacity(boxes.len()),
        };
        if !items.is_empty() {
            tree.nodes.push(Node::EMPTY);
            let (b, c) = tree.median(boxes, &mut items);
            tree.nodes[0].set(0, &b, c);
        }
        tree
    }

    fn median(&mut self, boxes: &[Aabb], items: &mut [(Vec3, u32)]) -> (Aabb, Child) {
        if items.len() == 1 {
            let i = items[0].1;
            return (boxes[i as usize], Child::Leaf { start: i, count: 1 });
        }
        let mut centres = Aabb::EMPTY;
        for (c, _) in items.iter() {
            centres.grow(*c);
        }
        let axis = (centres.max - centres.min).max_position();
        let mid = items.len() / 2;
        items.select_nth_unstable_by(mid, |x, y| {
            x.0[axis].total_cmp(&y.0[axis]).then(x.1.cmp(&y.1))
        });
        let (l, r) = items.split_at_mut(mid);
        let at = self.nodes.len();
        self.nodes.push(Node::EMPTY);
        let (bl, cl) = self.median(boxes, l);
        let (br, cr) = self.median(boxes, r);
        self.nodes[at].set(0, &bl, cl);
        self.nodes[at].set(1, &br, cr);
        (bl.union(&br), Child::Node(at as u32))
    }

    /// Bytes this tree holds.
    pub fn heap_bytes(&self) -> usize {
        self.nodes.capacity() * std::mem::size_of::<Node>()
    }

    /// Items whose leaf box lies within `bound_sq(…)` of `q`, nearest box
    /// first: `visit(box distance², item)` is called in that order and
    /// returns the bound for the rest (it may shrink as results come in).
    /// Stops at the first box beyond the bound. `heap` is scratch.
    pub fn nearest_leaves<E>(
        &self,
        q: &[f32; 3],
        mut bound_sq: f32,
        heap: &mut Vec<(f32, u32)>,
        mut visit: impl FnMut(f32, u32) -> Result<f32, E>,
    ) -> Result<(), E> {
        heap.clear();
        if self.nodes.is_empty() {
            return Ok(());
        }
        // Heap entries: a node as its index, a leaf item with the top bit.
        const ITEM: u32 = 1 << 31;
        push_min(heap, (0.0, 0));
        while let Some((d, e)) = pop_min(heap) {
            if d > bound_sq {
                break;
            }
            if e & ITEM != 0 {
                bound_sq = visit(d, e & !ITEM)?;
                continue;
            }
            let n = &self.nodes[e as usize];
            for i in 0..2 {
                let dc = n.distance_sq(i, q);
                if dc > bound_sq {
                    continue;
                }
                match n.child(i) {
                    Child::Node(c) => push_min(heap, (dc, c)),
                    Child::Leaf { start, count } => {
                        for item in start..start + count {
                            push_min(heap, (dc, item | ITEM));
                        }
                    }
                }
            }
        }
        Ok(())
    }
}

/// Order of the tile-box heap: distance, then node (deterministic ties).
#[inline(always)]
fn before(a: (f32, u32), b: (f32, u32)) -> bool {
    a.0 < b.0 || (a.0 == b.0 && a.1 < b.1)
}

fn push_min(h: &mut Vec<(f32, u32)>, v: (f32, u32)) {
    h.push(v);
    sift_up(h, before);
}

fn pop_min(h: &mut Vec<(f32, u32)>) -> Option<(f32, u32)> {
    let last = h.pop()?;
    let Some(&top) = h.first() else {
        return Some(last);
    };
    sift_down(h, last, before);
    Some(top)
}

#[cfg(test)]
mod tests;
