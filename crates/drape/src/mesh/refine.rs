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
//! **Undoing green splits** ([`refine_again`]). Green triangles refined
//! again would be bisected again and grow thin (two levels along a fold
//! brought the smallest angle from 30° to 11°). Refining a mesh that a
//! refinement made, the halves of each green split that is marked, or
//! that the closure reaches (an edge of a half split), are put back
//! together and their parent is split red instead — its split edge's
//! midpoint kept — as PLTMG does (Bank, Sherman & Weiser 1983). No
//! triangle is then bisected twice, and every triangle is similar to one
//! of the coarse mesh's, or a half of one.

use super::{ElementOrder, Mesh};
use std::collections::HashMap;

/// A refined mesh and where its parts came from.
#[derive(Debug, Clone)]
pub struct Refinement {
    /// The refined mesh: the coarse nodes first, in their order, then the
    /// new midpoints.
    pub mesh: Mesh,
    /// For each new node (`coarse node count + k`), the coarse edge it
    /// halves (a linear refinement; empty for [`refine_lagrange`], whose
    /// new nodes are not midpoints).
    pub midpoints: Vec<[usize; 2]>,
    /// For each triangle of the refined mesh, its coarse element.
    pub parent: Vec<usize>,
    /// How many coarse elements were split red (in four).
    pub red: usize,
    /// How many were halved (green).
    pub green: usize,
    /// The green splits, for a refinement of the refined mesh to undo
    /// ([`refine_again`]).
    pub greens: Vec<Green>,
}

/// A triangle halved green, in a refined mesh's numbering.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Green {
    /// The halved triangle's corners `(u, v, w)`, in its orientation, the
    /// split edge `u`–`v`.
    pub corners: [usize; 3],
    /// The split edge's midpoint, a node of the refined mesh.
    pub midpoint: usize,
    /// The two halves `(u, k, w)` and `(k, v, w)`: elements of the refined
    /// mesh.
    pub halves: [usize; 2],
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
    refine_again(mesh, marked, &[])
}

/// [`refine`] of a mesh that a refinement made, undoing its green splits
/// `greens` ([`Refinement::greens`]) where the refinement reaches them
/// (module docs): the halves of each such split are replaced by their
/// parent, which is split red. With no `greens`, [`refine`].
///
/// # Errors
/// [`RefineError`]: a mesh of higher order, or flags that do not match.
pub fn refine_again(
    mesh: &Mesh,
    marked: &[bool],
    greens: &[Green],
) -> Result<Refinement, RefineError> {
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
    let elements: Vec<[usize; 3]> = mesh.elements().map(|t| [t[0], t[1], t[2]]).collect();
    // Green splits undone: those marked, then those the closure reaches,
    // until none is reached.
    let mut undone: Vec<bool> = greens
        .iter()
        .map(|g| g.halves.iter().any(|&h| marked[h]))
        .collect();
    let (triangles, origin, red, mut split) = loop {
        let (triangles, origin, mut red, presplit) = working(&elements, marked, greens, &undone);
        let split = closure(&triangles, &mut red, presplit);
        let mut reached = false;
        for (g, green) in greens.iter().enumerate() {
            if !undone[g] && green.halves.iter().any(|&h| cut(&split, elements[h]) > 0) {
                undone[g] = true;
                reached = true;
            }
        }
        if !reached {
            break (triangles, origin, red, split);
        }
    };
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
    let (mut reds, mut halved) = (0, Vec::new());
    // Emits triangle `t` of element `e`: halved where one of its edges is
    // split (green), else whole.
    let mut emit = |[a, b, c]: [usize; 3], e: usize, parent: &mut Vec<usize>| {
        let cuts = [mid(a, b), mid(b, c), mid(c, a)];
        let green = [(a, b, c), (b, c, a), (c, a, b)]
            .into_iter()
            .zip(cuts)
            .find_map(|(v, k)| k.map(|k| (v, k)));
        match green {
            Some(((u, v, w), k)) => {
                let first = parent.len();
                connectivity.extend_from_slice(&[u, k, w, k, v, w]);
                parent.extend_from_slice(&[e; 2]);
                halved.push(Green {
                    corners: [u, v, w],
                    midpoint: k,
                    halves: [first, first + 1],
                });
            }
            None => {
                connectivity.extend_from_slice(&[a, b, c]);
                parent.push(e);
            }
        }
    };
    for (i, &[a, b, c]) in triangles.iter().enumerate() {
        let e = origin[i];
        // A red triangle's edges are all split; at most one edge of a
        // green one (two or three turned it red).
        if let (true, [Some(ab), Some(bc), Some(ca)]) = (red[i], [mid(a, b), mid(b, c), mid(c, a)])
        {
            reds += 1;
            // A child's outer edge is split only where it is half of an
            // undone green split's edge, which the refinement across it
            // splits again: that child is halved.
            for child in [[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]] {
                emit(child, e, &mut parent);
            }
            continue;
        }
        emit([a, b, c], e, &mut parent);
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
        green: halved.len(),
        greens: halved,
    })
}

/// Each triangle of a Lagrange mesh of order 2 or 3 split red into four,
/// every triangle (no closure is needed): the children's corners are the
/// parent's corners and its edges' midpoints in the parent's reference
/// coordinates, and each child's nodes are those of its order on it. A
/// node that is one of the parent's keeps its number; every other is
/// new, placed by the parent's own interpolation: with the rule (the
/// parent's nodes, the weights `phi^a(xi)`, summing to 1) that
/// [`crate::levels::Transfer`] carries a field by. A node on a coarse
/// edge depends on that edge's nodes alone, so the two triangles beside
/// it give it the same place, and it is made once. The refined mesh
/// represents each coarse element's field exactly (a polynomial of the
/// order on each child): a carried state has the coarse state's
/// energy.
///
/// Returns the refinement (`midpoints` empty: the new nodes are not
/// edge midpoints; no greens) and each new node's rule.
///
/// # Errors
/// [`RefineError::Order`] for a linear mesh (split by [`refine`]).
pub fn refine_lagrange(mesh: &Mesh) -> Result<(Refinement, Vec<Rule>), RefineError> {
    if mesh.order == ElementOrder::Linear {
        return Err(RefineError::Order(1));
    }
    let basis = super::lagrange::ShapeFunctions::new(mesh.order);
    let local = super::lagrange::reference_nodes(mesh.order);
    let p = mesh.order.degree();
    // Reference points of the children's nodes are multiples of 1 / (2p).
    let scale = (2 * p) as f64;
    let grid = |xi: [f64; 2]| {
        [
            (xi[0] * scale).round() as i64,
            (xi[1] * scale).round() as i64,
        ]
    };
    let children: [[[f64; 2]; 3]; 4] = [
        [[0.0, 0.0], [0.5, 0.0], [0.0, 0.5]],
        [[0.5, 0.0], [1.0, 0.0], [0.5, 0.5]],
        [[0.0, 0.5], [0.5, 0.5], [0.0, 1.0]],
        [[0.5, 0.0], [0.5, 0.5], [0.0, 0.5]],
    ];
    let mut nodes = mesh.nodes.clone();
    let mut rules: Vec<Rule> = Vec::new();
    let mut on_edges: HashMap<(usize, usize, i64), usize> = HashMap::new();
    let mut connectivity = Vec::with_capacity(4 * mesh.connectivity.len());
    let mut parent = Vec::with_capacity(4 * mesh.element_count());
    // The parent's nodes on the grid, and its new interior nodes (a few
    // per triangle: a short list, searched).
    let at: Vec<[i64; 2]> = local.iter().map(|xi| grid(*xi)).collect();
    let mut inside: Vec<([i64; 2], usize)> = Vec::new();
    for (e, element) in mesh.elements().enumerate() {
        let corners = [element[0], element[1], element[2]];
        inside.clear();
        for child in &children {
            for xi in &local {
                let x = std::array::from_fn(|i| {
                    child[0][i]
                        + xi[0] * (child[1][i] - child[0][i])
                        + xi[1] * (child[2][i] - child[0][i])
                });
                let key = grid(x);
                let node = if let Some(k) = at.iter().position(|&g| g == key) {
                    element[k]
                } else {
                    // Barycentric coordinates (in units of 1 / 2p): on an
                    // edge where one is zero.
                    let l = [2 * p as i64 - key[0] - key[1], key[0], key[1]];
                    let edge = (0..3).find(|&k| l[k] == 0).map(|k| {
                        let (i, j) = ((k + 1) % 3, (k + 2) % 3);
                        let (a, b) = (corners[i], corners[j]);
                        // The distance from the smaller end, in 1 / 2p.
                        if a < b { (a, b, l[j]) } else { (b, a, l[i]) }
                    });
                    let known = match edge {
                        Some(k) => on_edges.get(&k).copied(),
                        None => inside.iter().find(|(g, _)| *g == key).map(|&(_, a)| a),
                    };
                    known.unwrap_or_else(|| {
                        let (phi, _) = basis.evaluate(x);
                        let weights = phi[..element.len()].to_vec();
                        let new = nodes.len();
                        nodes.push(std::array::from_fn(|i| {
                            element
                                .iter()
                                .zip(&weights)
                                .map(|(&a, w)| w * mesh.nodes[a][i])
                                .sum()
                        }));
                        rules.push((element.to_vec(), weights));
                        if let Some(k) = edge {
                            on_edges.insert(k, new);
                        } else {
                            inside.push((key, new));
                        }
                        new
                    })
                };
                connectivity.push(node);
            }
            parent.push(e);
        }
    }
    let refinement = Refinement {
        mesh: Mesh {
            nodes,
            order: mesh.order,
            connectivity,
        },
        midpoints: Vec::new(),
        parent,
        red: mesh.element_count(),
        green: 0,
        greens: Vec::new(),
    };
    Ok((refinement, rules))
}

/// A new node's place as a combination of coarse nodes: their numbers and
/// weights (summing to 1).
pub type Rule = (Vec<usize>, Vec<f64>);

/// The edge `a`–`b` as a key, its ends in order.
fn key(a: usize, b: usize) -> (usize, usize) {
    (a.min(b), a.max(b))
}

/// How many of triangle `t`'s edges `split` holds.
fn cut(split: &HashMap<(usize, usize), usize>, t: [usize; 3]) -> usize {
    (0..3)
        .filter(|&m| split.contains_key(&key(t[m], t[(m + 1) % 3])))
        .count()
}

/// The triangles a refinement splits — `elements`, the halves of each
/// `undone` green split replaced by its parent (at the first half's place)
/// — with each one's element, its red mark (`marked`, and every undone
/// parent), and the undone parents' split edges with their midpoints.
#[allow(clippy::type_complexity)]
fn working(
    elements: &[[usize; 3]],
    marked: &[bool],
    greens: &[Green],
    undone: &[bool],
) -> (
    Vec<[usize; 3]>,
    Vec<usize>,
    Vec<bool>,
    HashMap<(usize, usize), usize>,
) {
    let mut replaced: HashMap<usize, Option<&Green>> = HashMap::new();
    for (green, _) in greens.iter().zip(undone).filter(|&(_, &u)| u) {
        replaced.insert(green.halves[0], Some(green));
        replaced.insert(green.halves[1], None);
    }
    let mut triangles = Vec::with_capacity(elements.len());
    let mut origin = Vec::with_capacity(elements.len());
    let mut red = Vec::with_capacity(elements.len());
    let mut presplit = HashMap::new();
    for (e, &t) in elements.iter().enumerate() {
        match replaced.get(&e) {
            None => {
                triangles.push(t);
                red.push(marked[e]);
            }
            Some(Some(green)) => {
                let [u, v, _] = green.corners;
                triangles.push(green.corners);
                red.push(true);
                presplit.insert(key(u, v), green.midpoint);
            }
            Some(None) => continue,
        }
        origin.push(e);
    }
    (triangles, origin, red, presplit)
}

/// The red–green closure of `triangles` whose red ones are `red`: every
/// edge of a red triangle is split, and a triangle with two split edges
/// turns red (and `red` says so). Returns the split edges, each with its
/// midpoint node where it has one already (`presplit`), else `usize::MAX`.
fn closure(
    triangles: &[[usize; 3]],
    red: &mut [bool],
    presplit: HashMap<(usize, usize), usize>,
) -> HashMap<(usize, usize), usize> {
    // The triangles of each edge.
    let mut beside: HashMap<(usize, usize), Vec<usize>> = HashMap::new();
    for (e, t) in triangles.iter().enumerate() {
        for m in 0..3 {
            beside.entry(key(t[m], t[(m + 1) % 3])).or_default().push(e);
        }
    }
    let mut split = presplit;
    let mut queue: Vec<usize> = (0..triangles.len()).filter(|&e| red[e]).collect();
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
                if !red[n] && cut(&split, triangles[n]) >= 2 {
                    red[n] = true;
                    queue.push(n);
                }
            }
        }
    }
    split
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

    /// The smallest angle of any triangle of a flat mesh (degrees).
    fn smallest_angle(mesh: &Mesh) -> f64 {
        mesh.elements()
            .flat_map(|t| {
                let p = [t[0], t[1], t[2]].map(|k| mesh.nodes[k]);
                (0..3).map(move |m| {
                    let (a, b, c) = (p[m], p[(m + 1) % 3], p[(m + 2) % 3]);
                    let u = [b[0] - a[0], b[1] - a[1]];
                    let v = [c[0] - a[0], c[1] - a[1]];
                    let cos = (u[0] * v[0] + u[1] * v[1])
                        / ((u[0] * u[0] + u[1] * u[1]) * (v[0] * v[0] + v[1] * v[1])).sqrt();
                    cos.clamp(-1.0, 1.0).acos().to_degrees()
                })
            })
            .fold(f64::INFINITY, f64::min)
    }

    /// The total length of the edges of one triangle: the boundary, and
    /// around any hanging node the edges beside it.
    fn open_length(mesh: &Mesh) -> f64 {
        let mut edges: HashMap<(usize, usize), usize> = HashMap::new();
        for t in mesh.elements() {
            for m in 0..3 {
                *edges.entry(key(t[m], t[(m + 1) % 3])).or_default() += 1;
            }
        }
        edges
            .iter()
            .filter(|&(_, &n)| n == 1)
            .map(|(&(a, b), _)| {
                let (p, q) = (mesh.nodes[a], mesh.nodes[b]);
                ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2)).sqrt()
            })
            .sum()
    }

    /// Three levels of local refinement, each marking the red children of
    /// the one before, whose closure reaches the green halves beside
    /// them: undoing those green splits keeps the smallest angle at a
    /// green split's of the coarse shapes (10.9° on the disc, whose
    /// triangles have 30° and more), where halving the halves again thins
    /// them at every level (6.7°, then 3.2°); every mesh conforming (no
    /// open edge but the boundary) and of the coarse area; and with no
    /// green splits to undo, `refine_again` is `refine`.
    #[test]
    fn refining_again_undoes_the_green_splits() {
        let coarse = disc(0.15, 6, [0.0; 3], ElementOrder::Linear);
        let mut marked = vec![false; coarse.element_count()];
        for e in 40..46 {
            marked[e] = true;
        }
        let first = refine(&coarse, &marked).unwrap();
        assert!(first.green > 0 && first.greens.len() == first.green);
        let fine = &first.mesh;
        // The first level's red children: the closure reaches the green
        // halves beside them, which a plain refinement halves again.
        let touched: Vec<bool> = (0..fine.element_count())
            .map(|e| {
                first
                    .parent
                    .iter()
                    .filter(|&&p| p == first.parent[e])
                    .count()
                    == 4
            })
            .collect();
        let plain = refine(fine, &touched).unwrap();
        let again = refine_again(fine, &touched, &first.greens).unwrap();
        let boundary = open_length(&coarse);
        for (name, r) in [("plain", &plain), ("undoing", &again)] {
            r.mesh.validate().unwrap();
            assert!(
                (area(&r.mesh) - area(&coarse)).abs() < 1e-14 * area(&coarse),
                "{name}"
            );
            let open = open_length(&r.mesh);
            assert!(
                (open - boundary).abs() < 1e-12,
                "{name}: open edges {open} m against {boundary} m"
            );
        }
        let (a0, a1, a2, a3) = (
            smallest_angle(&coarse),
            smallest_angle(fine),
            smallest_angle(&plain.mesh),
            smallest_angle(&again.mesh),
        );
        // A third level, marking the second's red children.
        let third = |r: &Refinement, undo: bool| {
            let touched: Vec<bool> = (0..r.mesh.element_count())
                .map(|e| r.parent.iter().filter(|&&p| p == r.parent[e]).count() == 4)
                .collect();
            let greens = if undo { r.greens.as_slice() } else { &[] };
            let t = refine_again(&r.mesh, &touched, greens).unwrap();
            t.mesh.validate().unwrap();
            assert!((open_length(&t.mesh) - boundary).abs() < 1e-12);
            smallest_angle(&t.mesh)
        };
        let (b2, b3) = (third(&plain, false), third(&again, true));
        eprintln!(
            "smallest angle: coarse {a0:.1}°, one level {a1:.1}°; two levels {a2:.1}° plain, \
             {a3:.1}° undoing greens; three {b2:.1}° plain, {b3:.1}° undoing"
        );
        // A green split of a triangle similar to a coarse one is as thin
        // as it gets (10.9° here); a green half halved again is thinner
        // at every level.
        assert!(b3 >= a3 - 1e-9 && a3 > 10.0, "undoing: {a3}°, then {b3}°");
        assert!(
            b2 < a2 && a2 < a3,
            "plain: {a2}°, then {b2}°, against {a3}°"
        );
        // Nothing to undo: the same refinement.
        let same = refine_again(&coarse, &marked, &[]).unwrap();
        assert_eq!(same.mesh.connectivity, first.mesh.connectivity);
        assert_eq!(same.mesh.nodes, first.mesh.nodes);
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
