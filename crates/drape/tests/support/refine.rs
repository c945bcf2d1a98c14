//! Local refinement of a T3 mesh for the tests: red splits (each triangle
//! into four at its edges' midpoints) where asked, and a green closure
//! (each triangle with one split edge halved from its opposite vertex), so
//! that no node hangs; a triangle with two or three split edges is split
//! red too, until none is left.

use drape::mesh::{ElementOrder, Mesh};
use std::collections::{HashMap, HashSet};

/// `mesh` with the triangles whose centroid `inside` accepts split in four
/// and a conforming closure around them.
pub fn split(mesh: &Mesh, inside: impl Fn([f64; 3]) -> bool) -> Mesh {
    assert_eq!(mesh.order, ElementOrder::Linear);
    let triangles: Vec<[usize; 3]> = mesh
        .connectivity
        .chunks(3)
        .map(|t| [t[0], t[1], t[2]])
        .collect();
    let key = |a: usize, b: usize| (a.min(b), a.max(b));
    let mut red: Vec<bool> = triangles
        .iter()
        .map(|t| {
            let c = [0, 1, 2].map(|i| t.iter().map(|&a| mesh.nodes[a][i]).sum::<f64>() / 3.0);
            inside(c)
        })
        .collect();
    // Marked edges: every edge of a red triangle; a triangle with two or
    // more marked edges turns red.
    let mut marked: HashSet<(usize, usize)> = HashSet::new();
    loop {
        marked.clear();
        for (t, tri) in triangles.iter().enumerate() {
            if red[t] {
                for m in 0..3 {
                    marked.insert(key(tri[m], tri[(m + 1) % 3]));
                }
            }
        }
        let mut changed = false;
        for (t, tri) in triangles.iter().enumerate() {
            let count = (0..3)
                .filter(|&m| marked.contains(&key(tri[m], tri[(m + 1) % 3])))
                .count();
            if !red[t] && count >= 2 {
                red[t] = true;
                changed = true;
            }
        }
        if !changed {
            break;
        }
    }
    let mut nodes = mesh.nodes.clone();
    let mut middle: HashMap<(usize, usize), usize> = HashMap::new();
    let mut mid = |a: usize, b: usize, nodes: &mut Vec<[f64; 3]>| -> usize {
        *middle.entry(key(a, b)).or_insert_with(|| {
            nodes.push([0, 1, 2].map(|i| 0.5 * (nodes[a][i] + nodes[b][i])));
            nodes.len() - 1
        })
    };
    let mut connectivity = Vec::new();
    for (t, &[a, b, c]) in triangles.iter().enumerate() {
        if red[t] {
            let (ab, bc, ca) = (
                mid(a, b, &mut nodes),
                mid(b, c, &mut nodes),
                mid(c, a, &mut nodes),
            );
            connectivity.extend_from_slice(&[a, ab, ca, ab, b, bc, ca, bc, c, ab, bc, ca]);
            continue;
        }
        let split = [(a, b, c), (b, c, a), (c, a, b)]
            .into_iter()
            .find(|&(u, v, _)| marked.contains(&key(u, v)));
        match split {
            Some((u, v, w)) => {
                let k = mid(u, v, &mut nodes);
                connectivity.extend_from_slice(&[u, k, w, k, v, w]);
            }
            None => connectivity.extend_from_slice(&[a, b, c]),
        }
    }
    let refined = Mesh {
        nodes,
        order: ElementOrder::Linear,
        connectivity,
    };
    refined.validate().expect("a valid refined mesh");
    refined
}
