//! Local refinement of a linear (T3) mesh: red splits where asked, a green
//! closure around them, no hanging node.
//!
//! A **red** split cuts a triangle into four at its edges' midpoints (the
//! middle one its medial triangle, similar to it: no angle degrades). A
//! triangle beside the red region with **one** split edge is halved from
//! its opposite vertex to that edge's midpoint (**green**); one with two
//! or three split edges is split red as well, and the marking repeats
//! until no triangle has two (Bank, Sherman & Weiser 1983, "Refinement
//! algorithms and data structures for regular local mesh refinement",
//! Scientific Computing, IMACS; the red–green refinement of PLTMG). The
//! result is conforming: every new node is the midpoint of an edge that
//! every triangle beside it splits too.
//!
//! New nodes are the midpoints of the reference edges; [`Refinement`]
//! records which edge each halves and which element each new triangle
//! came from, so that a state on the coarse mesh can be carried over
//! (positions of a curved current surface, velocities). Each new triangle
//! keeps its parent's orientation. Area is conserved exactly on a flat
//! mesh: the children of a triangle tile it.
//!
//! Green triangles refined again would be bisected again and grow thin;
//! a multilevel refinement should undo a green split and split its parent
//! red instead (not done here: one level at a time).

use super::{ElementOrder, Mesh};
use std::collections::HashMap;

/// A refined mesh and where its parts came from.
#[derive(Debug, Clone)]
pub struct Refinement {
    /// The refined mesh: the coarse nodes first, in their order, then the
    /// new midpoints.
    pub mesh: Mesh,
    /// For each new node (`coarse node count + k`), the coarse edge it
    /// halves.
    pub midpoints: Vec<[usize; 2]>,
    /// For each triangle of the refined mesh, its coarse element.
    pub parent: Vec<usize>,
    /// How many coarse elements were split red (in four).
    pub red: usize,
    /// How many were halved (green).
    pub green: usize,
}

/// Why a mesh cannot be refined.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum RefineError {
    /// Only linear triangles are refined.
    #[error(
        "refinement takes linear triangles (order 1); this mesh has order {0}: refine before elevating the order"
    )]
    Order(usize),
    /// `marked` does not have one flag per element.
    #[error("{given} refinement flags for {elements} elements")]
    Flags {
        /// Flags given.
        given: usize,
        /// Elements of the mesh.
        elements: usize,
    },
}

/// `mesh` with the elements `marked` split red and a green closure around
/// them (module docs).
///
/// # Errors
/// [`RefineError`]: a mesh of higher order, or flags that do not match.
pub fn refine(mesh: &Mesh, marked: &[bool]) -> Result<Refinement, RefineError> {
    if mesh.order != ElementOrder::Linear {
        return Err(RefineError::Order(mesh.order.degree()));
    }
    let count = mesh.element_count();
    if marked.len() != count {
        return Err(RefineError::Flags {
            given: marked.len(),
            elements: count,
        });
    }
    let triangles: Vec<[usize; 3]> = mesh.elements().map(|t| [t[0], t[1], t[2]]).collect();
    let key = |a: usize, b: usize| (a.min(b), a.max(b));
    // The elements of each edge.
    let mut beside: HashMap<(usize, usize), Vec<usize>> = HashMap::new();
    for (e, t) in triangles.iter().enumerate() {
        for m in 0..3 {
            beside.entry(key(t[m], t[(m + 1) % 3])).or_default().push(e);
        }
    }
    let mut red = marked.to_vec();
    let mut split: HashMap<(usize, usize), usize> = HashMap::new();
    let mut queue: Vec<usize> = (0..count).filter(|&e| red[e]).collect();
    // Marks the edges of each red triangle; a neighbour with two split
    // edges turns red in its turn.
    while let Some(e) = queue.pop() {
        let t = triangles[e];
        for m in 0..3 {
            let k = key(t[m], t[(m + 1) % 3]);
            if split.contains_key(&k) {
                continue;
            }
            split.insert(k, usize::MAX);
            for &n in beside.get(&k).map(Vec::as_slice).unwrap_or(&[]) {
                if red[n] {
                    continue;
                }
                let u = triangles[n];
                let cut = (0..3)
                    .filter(|&i| split.contains_key(&key(u[i], u[(i + 1) % 3])))
                    .count();
                if cut >= 2 {
                    red[n] = true;
                    queue.push(n);
                }
            }
        }
    }
    // New nodes in the order of the elements and their edges (a result
    // that depends on the mesh alone).
    let mut nodes = mesh.nodes.clone();
    let mut midpoints = Vec::new();
    for t in &triangles {
        for m in 0..3 {
            let (a, b) = (t[m], t[(m + 1) % 3]);
            let (p, q) = key(a, b);
            match split.get_mut(&(p, q)) {
                Some(slot) if *slot == usize::MAX => {
                    *slot = nodes.len();
                    let (pa, pb) = (mesh.nodes[a], mesh.nodes[b]);
                    nodes.push(std::array::from_fn(|i| 0.5 * (pa[i] + pb[i])));
                    midpoints.push([p, q]);
                }
                _ => {}
            }
        }
    }
    let mid = |a: usize, b: usize| split.get(&key(a, b)).copied();
    let mut connectivity = Vec::with_capacity(3 * (count + 3 * midpoints.len()));
    let mut parent = Vec::with_capacity(count + 3 * midpoints.len());
    let (mut reds, mut greens) = (0, 0);
    for (e, &[a, b, c]) in triangles.iter().enumerate() {
        let cuts = [mid(a, b), mid(b, c), mid(c, a)];
        // A red triangle's edges are all split.
        if let (true, [Some(ab), Some(bc), Some(ca)]) = (red[e], cuts) {
            connectivity.extend_from_slice(&[a, ab, ca, ab, b, bc, ca, bc, c, ab, bc, ca]);
            parent.extend_from_slice(&[e; 4]);
            reds += 1;
            continue;
        }
        // At most one split edge (two or three turned it red).
        let green = [(a, b, c), (b, c, a), (c, a, b)]
            .into_iter()
            .zip(cuts)
            .find_map(|(v, k)| k.map(|k| (v, k)));
        match green {
            Some(((u, v, w), k)) => {
                connectivity.extend_from_slice(&[u, k, w, k, v, w]);
                parent.extend_from_slice(&[e; 2]);
                greens += 1;
            }
            None => {
                connectivity.extend_from_slice(&[a, b, c]);
                parent.push(e);
            }
        }
    }
    Ok(Refinement {
        mesh: Mesh {
            nodes,
            order: ElementOrder::Linear,
            connectivity,
        },
        midpoints,
        parent,
        red: reds,
        green: greens,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate::{Pattern, disc, rectangle};

    /// The area of a flat mesh in z = const.
    fn area(mesh: &Mesh) -> f64 {
        mesh.elements()
            .map(|t| {
                let [a, b, c] = [t[0], t[1], t[2]].map(|k| mesh.nodes[k]);
                0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))
            })
            .sum()
    }

    /// Every edge of `mesh` belongs to one or two triangles, and a new
    /// node on the coarse boundary lies on a boundary edge of the fine
    /// mesh: no node hangs on an edge it does not split.
    fn assert_conforming(coarse: &Mesh, r: &Refinement) {
        let mut edges: HashMap<(usize, usize), usize> = HashMap::new();
        for t in r.mesh.elements() {
            for m in 0..3 {
                let (a, b) = (t[m], t[(m + 1) % 3]);
                *edges.entry((a.min(b), a.max(b))).or_default() += 1;
            }
        }
        assert!(edges.values().all(|&n| n <= 2));
        // A hanging node sits inside an edge of the fine mesh: check that
        // no midpoint lies on the segment of an edge it is not an end of.
        for (k, [a, b]) in r.midpoints.iter().enumerate() {
            let m = coarse.node_count() + k;
            assert!(
                !edges.contains_key(&((*a).min(*b), (*a).max(*b))),
                "edge {a}-{b} still whole beside its midpoint {m}"
            );
        }
    }

    /// Every element split: four times the triangles, every edge halved,
    /// the area to round-off, a valid mesh.
    #[test]
    fn uniform_refinement_quadruples_the_triangles() {
        for pattern in [Pattern::Right, Pattern::Alternate] {
            let coarse = rectangle([0.3, 0.2], [6, 4], pattern, [0.0; 3], ElementOrder::Linear);
            let r = refine(&coarse, &vec![true; coarse.element_count()]).unwrap();
            r.mesh.validate().unwrap();
            assert_eq!(r.mesh.element_count(), 4 * coarse.element_count());
            assert_eq!((r.red, r.green), (coarse.element_count(), 0));
            // Edges of a 6 x 4 grid of squares cut in two: 7 x 4 + 6 x 5 + 24.
            assert_eq!(r.midpoints.len(), 7 * 4 + 6 * 5 + 24);
            assert!((area(&r.mesh) - 0.06).abs() < 1e-15, "{}", area(&r.mesh));
            assert_conforming(&coarse, &r);
            assert!(r.parent.iter().all(|&p| p < coarse.element_count()));
        }
    }

    /// One marked triangle in a disc: it and the closure around it, a valid
    /// conforming mesh of the same area (to round-off); the unmarked far
    /// away untouched.
    #[test]
    fn local_refinement_closes_conformingly() {
        let coarse = disc(0.15, 6, [0.0; 3], ElementOrder::Linear);
        let mut marked = vec![false; coarse.element_count()];
        marked[40] = true;
        marked[41] = true;
        let r = refine(&coarse, &marked).unwrap();
        r.mesh.validate().unwrap();
        assert!(
            r.red >= 2 && r.green >= 1,
            "{} red, {} green",
            r.red,
            r.green
        );
        assert_eq!(
            r.mesh.element_count(),
            coarse.element_count() + 3 * r.red + r.green
        );
        assert!((area(&r.mesh) - area(&coarse)).abs() < 1e-15 * area(&coarse));
        assert_conforming(&coarse, &r);
        // Elements that were not touched keep their nodes.
        let kept = r
            .parent
            .iter()
            .enumerate()
            .filter(|&(_, &p)| r.parent.iter().filter(|&&q| q == p).count() == 1)
            .count();
        assert_eq!(kept, coarse.element_count() - r.red - r.green);
    }

    /// Marking the lower triangle of each square of a strip turns the
    /// upper ones red too (each has two split edges: its diagonal and the
    /// side it shares with the square before), all but the first, whose
    /// side is the strip's end: it is halved. No mark refines nothing.
    #[test]
    fn the_closure_spreads_and_nothing_marked_changes_nothing() {
        let coarse = rectangle(
            [0.4, 0.1],
            [4, 1],
            Pattern::Right,
            [0.0; 3],
            ElementOrder::Linear,
        );
        let marked: Vec<bool> = (0..coarse.element_count()).map(|e| e % 2 == 0).collect();
        let r = refine(&coarse, &marked).unwrap();
        assert_eq!((r.red, r.green), (coarse.element_count() - 1, 1));
        r.mesh.validate().unwrap();
        let none = refine(&coarse, &vec![false; coarse.element_count()]).unwrap();
        assert_eq!(none.mesh.connectivity, coarse.connectivity);
        assert!(none.midpoints.is_empty());
    }

    /// Higher orders and mismatched flags are refused, saying why.
    #[test]
    fn bad_input_is_refused() {
        let t6 = rectangle(
            [0.1, 0.1],
            [2, 2],
            Pattern::Right,
            [0.0; 3],
            ElementOrder::Quadratic,
        );
        let e = refine(&t6, &vec![true; t6.element_count()]).unwrap_err();
        assert!(e.to_string().contains("order 2"), "{e}");
        let t3 = rectangle(
            [0.1, 0.1],
            [2, 2],
            Pattern::Right,
            [0.0; 3],
            ElementOrder::Linear,
        );
        let e = refine(&t3, &[true]).unwrap_err();
        assert_eq!(e.to_string(), "1 refinement flags for 8 elements");
    }
}
