//! Bounding volume hierarchy for nearest-item queries: a binary tree of
//! axis-aligned bounding boxes (AABB), built by median splits.
//!
//! Each inner node splits its items at the median of their box centres
//! along the longest axis of the centres' bounds, so the tree is balanced
//! (depth at most `log2(n / LEAF_SIZE) + 2`) whatever the mesh. A query
//! descends the nearer child first and skips every node whose box is
//! farther than the best distance found so far (plus a slack), so a query
//! visits `O(log n)` nodes for a point near a well-shaped surface. Queries
//! allocate nothing.

use crate::vec3::norm;

/// Items per leaf.
const LEAF_SIZE: usize = 4;

/// Largest depth a query's stack supports: a balanced tree over at most
/// `u32::MAX` items has depth at most 32.
const STACK_SIZE: usize = 64;

/// A node of the tree.
#[derive(Debug, Clone)]
struct Node {
    lo: [f64; 3],
    hi: [f64; 3],
    /// Leaf: index of the first item in `items`; inner node: index of the
    /// right child (the left child follows the node).
    start: usize,
    /// Number of items of a leaf; 0 for an inner node.
    count: usize,
}

/// An AABB tree over items numbered `0..n`, each given by its box.
#[derive(Debug, Clone)]
pub(super) struct Bvh {
    nodes: Vec<Node>,
    items: Vec<u32>,
}

/// Euclidean distance from `p` to the box `[lo, hi]` (0 inside).
fn box_distance(p: [f64; 3], lo: [f64; 3], hi: [f64; 3]) -> f64 {
    let mut excess = [0.0; 3];
    for k in 0..3 {
        excess[k] = (lo[k] - p[k]).max(p[k] - hi[k]).max(0.0);
    }
    norm(excess)
}

impl Bvh {
    /// Builds the tree over the boxes `(lo, hi)` of items `0..boxes.len()`
    /// (at most `u32::MAX` items).
    pub(super) fn new(boxes: &[([f64; 3], [f64; 3])]) -> Self {
        let mut tree = Self {
            nodes: Vec::with_capacity(2 * boxes.len() / LEAF_SIZE + 1),
            items: (0..boxes.len() as u32).collect(),
        };
        if !boxes.is_empty() {
            tree.build(0, boxes.len(), boxes);
        }
        tree
    }

    /// Adds the subtree over `items[first..end]`; returns its node index.
    fn build(&mut self, first: usize, end: usize, boxes: &[([f64; 3], [f64; 3])]) -> usize {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        let mut centre_lo = [f64::INFINITY; 3];
        let mut centre_hi = [f64::NEG_INFINITY; 3];
        for &i in &self.items[first..end] {
            let (a, b) = boxes[i as usize];
            for k in 0..3 {
                lo[k] = lo[k].min(a[k]);
                hi[k] = hi[k].max(b[k]);
                let c = 0.5 * (a[k] + b[k]);
                centre_lo[k] = centre_lo[k].min(c);
                centre_hi[k] = centre_hi[k].max(c);
            }
        }
        let index = self.nodes.len();
        self.nodes.push(Node {
            lo,
            hi,
            start: first,
            count: end - first,
        });
        if end - first <= LEAF_SIZE {
            return index;
        }
        let axis = (0..3)
            .max_by(|&i, &j| {
                (centre_hi[i] - centre_lo[i]).total_cmp(&(centre_hi[j] - centre_lo[j]))
            })
            .unwrap_or(0);
        let mid = first + (end - first) / 2;
        let centre = |i: &u32| {
            let (a, b) = boxes[*i as usize];
            a[axis] + b[axis]
        };
        self.items[first..end]
            .select_nth_unstable_by(mid - first, |i, j| centre(i).total_cmp(&centre(j)));
        self.build(first, mid, boxes);
        let right = self.build(mid, end, boxes);
        let node = &mut self.nodes[index];
        node.start = right;
        node.count = 0;
        index
    }

    /// Visits the items that may lie within `best + slack` of `p`, nearest
    /// boxes first. `visit(item)` evaluates an item and returns the best
    /// (smallest) distance the caller has found so far, which prunes the
    /// rest of the search: every item whose distance to `p` is at most the
    /// final best distance plus `slack` is visited. `initial` is a known
    /// bound on that distance (`f64::INFINITY` if none).
    pub(super) fn visit_nearest(
        &self,
        p: [f64; 3],
        initial: f64,
        slack: f64,
        mut visit: impl FnMut(u32) -> f64,
    ) {
        let Some(root) = self.nodes.first() else {
            return;
        };
        let mut best = initial;
        let mut stack = [(0usize, 0.0f64); STACK_SIZE];
        let mut depth = 0;
        let mut current = (0, box_distance(p, root.lo, root.hi));
        loop {
            let (index, distance) = current;
            if distance <= best + slack {
                let node = &self.nodes[index];
                if node.count > 0 {
                    for &item in &self.items[node.start..node.start + node.count] {
                        best = best.min(visit(item));
                    }
                } else {
                    let (left, right) = (index + 1, node.start);
                    let dl = box_distance(p, self.nodes[left].lo, self.nodes[left].hi);
                    let dr = box_distance(p, self.nodes[right].lo, self.nodes[right].hi);
                    let (near, far) = if dl <= dr {
                        ((left, dl), (right, dr))
                    } else {
                        ((right, dr), (left, dl))
                    };
                    // The tree is balanced, so the stack cannot overflow.
                    if let Some(slot) = stack.get_mut(depth) {
                        *slot = far;
                        depth += 1;
                    }
                    current = near;
                    continue;
                }
            }
            if depth == 0 {
                break;
            }
            depth -= 1;
            current = stack[depth];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Nearest point of a cloud (items are points, boxes degenerate) against
    /// brute force.
    #[test]
    fn nearest_point_of_a_cloud_matches_brute_force() {
        let mut state: u64 = 3;
        let mut rand = || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let points: Vec<[f64; 3]> = (0..1000).map(|_| [rand(), rand(), rand()]).collect();
        let boxes: Vec<_> = points.iter().map(|&p| (p, p)).collect();
        let tree = Bvh::new(&boxes);
        let mut visited_total = 0;
        for _ in 0..200 {
            let q = [2.0 * rand() - 0.5, 2.0 * rand() - 0.5, 2.0 * rand() - 0.5];
            let exact = points
                .iter()
                .map(|&p| norm(crate::vec3::sub(p, q)))
                .fold(f64::INFINITY, f64::min);
            let mut found = f64::INFINITY;
            tree.visit_nearest(q, f64::INFINITY, 0.0, |i| {
                visited_total += 1;
                found = found.min(norm(crate::vec3::sub(points[i as usize], q)));
                found
            });
            assert_eq!(found, exact);
        }
        // Pruning works: far fewer than 1000 points per query.
        assert!(visited_total < 200 * 200, "{visited_total}");
    }

    #[test]
    fn empty_and_single() {
        let tree = Bvh::new(&[]);
        tree.visit_nearest([0.0; 3], f64::INFINITY, 0.0, |_| panic!("no items"));
        let tree = Bvh::new(&[([0.0; 3], [1.0; 3])]);
        let mut seen = 0;
        tree.visit_nearest([5.0; 3], f64::INFINITY, 0.0, |_| {
            seen += 1;
            1.0
        });
        assert_eq!(seen, 1);
        // A NaN point visits nothing and does not panic.
        tree.visit_nearest([f64::NAN; 3], f64::INFINITY, 0.0, |_| 0.0);
    }
}
