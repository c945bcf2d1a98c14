//! Structured mesh generators: rectangle and disc, of order 1–3.
//!
//! Both build linear triangles, counter-clockwise seen from +z, and then
//! [`elevate`] adds the high-order nodes (straight edges; on the disc's rim
//! the edge nodes are moved onto the circle).

use super::{ElementOrder, Mesh};

/// How each square of a rectangle is cut into two triangles.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Pattern {
    /// Diagonal from the square's min corner to its max corner.
    Right,
    /// Diagonal from `(x_max, y_min)` to `(x_min, y_max)`.
    Left,
    /// Alternating diagonals (the "union jack"), symmetric about both
    /// axes when the division counts are even.
    Alternate,
}

/// A `size[0] x size[1]` rectangle centred on `center`, in the plane `z =
/// center[2]`, with `divisions[0] x divisions[1]` squares each cut into two
/// triangles.
pub fn rectangle(
    size: [f64; 2],
    divisions: [usize; 2],
    pattern: Pattern,
    center: [f64; 3],
    order: ElementOrder,
) -> Mesh {
    let [nx, ny] = divisions;
    let linear = grid(size, divisions, center, |i, j| match pattern {
        Pattern::Right => true,
        Pattern::Left => false,
        // Union jack: the diagonals point away from the centre.
        Pattern::Alternate => (2 * i + 1 < nx) == (2 * j + 1 < ny),
    });
    elevate(&linear, order)
}

/// [`rectangle`]'s linear triangles with each square's diagonal chosen by
/// `right(i, j)` for square `(i, j)` (`i` along x from the min corner):
/// `true` from its min to its max corner, `false` the other one. Node
/// `(i, j)` of the lattice is node `j (divisions[0] + 1) + i`.
pub fn grid(
    size: [f64; 2],
    divisions: [usize; 2],
    center: [f64; 3],
    right: impl Fn(usize, usize) -> bool,
) -> Mesh {
    let [nx, ny] = divisions;
    let mut nodes = Vec::with_capacity((nx + 1) * (ny + 1));
    for j in 0..=ny {
        for i in 0..=nx {
            nodes.push([
                center[0] - 0.5 * size[0] + size[0] * i as f64 / nx as f64,
                center[1] - 0.5 * size[1] + size[1] * j as f64 / ny as f64,
                center[2],
            ]);
        }
    }
    let id = |i: usize, j: usize| j * (nx + 1) + i;
    let mut connectivity = Vec::with_capacity(6 * nx * ny);
    for j in 0..ny {
        for i in 0..nx {
            let (p00, p10, p11, p01) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            if right(i, j) {
                connectivity.extend_from_slice(&[p00, p10, p11, p00, p11, p01]);
            } else {
                connectivity.extend_from_slice(&[p00, p10, p01, p10, p11, p01]);
            }
        }
    }
    Mesh {
        nodes,
        order: ElementOrder::Linear,
        connectivity,
    }
}

/// A disc of radius `radius` centred on `center` in the plane `z =
/// center[2]`: a centre node and `rings` concentric rings, ring `k` with `6k`
/// equally spaced nodes, zipped together by angle.
pub fn disc(radius: f64, rings: usize, center: [f64; 3], order: ElementOrder) -> Mesh {
    let mut nodes = vec![center];
    let mut ring_start = vec![0usize];
    for k in 1..=rings {
        ring_start.push(nodes.len());
        let r = radius * k as f64 / rings as f64;
        for j in 0..6 * k {
            let theta = 2.0 * std::f64::consts::PI * j as f64 / (6 * k) as f64;
            nodes.push([
                center[0] + r * theta.cos(),
                center[1] + r * theta.sin(),
                center[2],
            ]);
        }
    }
    let mut connectivity = Vec::new();
    for k in 1..=rings {
        let inner: Vec<usize> = if k == 1 {
            vec![0]
        } else {
            (0..6 * (k - 1)).map(|j| ring_start[k - 1] + j).collect()
        };
        let outer: Vec<usize> = (0..6 * k).map(|j| ring_start[k] + j).collect();
        // Walk both rings once around, always advancing the one whose next
        // node comes first in angle (the centre "ring" never advances).
        let (ni, no) = (inner.len(), outer.len());
        let (mut i, mut o) = (usize::from(ni == 1), 0usize);
        while i < ni || o < no {
            let next_inner = (i + 1) as f64 / ni as f64;
            let next_outer = (o + 1) as f64 / no as f64;
            if o < no && (i >= ni || next_outer <= next_inner) {
                connectivity.extend_from_slice(&[
                    inner[i % ni],
                    outer[o % no],
                    outer[(o + 1) % no],
                ]);
                o += 1;
            } else {
                connectivity.extend_from_slice(&[
                    inner[i % ni],
                    outer[o % no],
                    inner[(i + 1) % ni],
                ]);
                i += 1;
            }
        }
    }
    let linear = Mesh {
        nodes,
        order: ElementOrder::Linear,
        connectivity,
    };
    elevate(&linear, order).project_rim(center, radius)
}

impl Mesh {
    /// Places the high-order nodes of the rim edges on the circle of
    /// `radius` about `center`, equally spaced in angle, and (order 3) the
    /// interior node of each element at `1/4 sum(edge nodes) - 1/6
    /// sum(vertices)` (the centroid for straight edges): curved,
    /// isoparametric rim elements.
    fn project_rim(mut self, center: [f64; 3], radius: f64) -> Mesh {
        let p = self.order.degree();
        if p == 1 {
            return self;
        }
        let npe = self.order.nodes_per_element();
        let angle = |x: [f64; 3]| (x[1] - center[1]).atan2(x[0] - center[0]);
        let on_rim = |x: [f64; 3]| {
            ((x[0] - center[0]).hypot(x[1] - center[1]) - radius).abs() < 1e-9 * radius
        };
        for e in 0..self.element_count() {
            let el: Vec<usize> = self.element(e).to_vec();
            for k in 0..3 {
                let (a, b) = (self.nodes[el[k]], self.nodes[el[(k + 1) % 3]]);
                if !(on_rim(a) && on_rim(b)) {
                    continue;
                }
                let (ta, mut tb) = (angle(a), angle(b));
                let pi = std::f64::consts::PI;
                if tb - ta > pi {
                    tb -= 2.0 * pi;
                } else if ta - tb > pi {
                    tb += 2.0 * pi;
                }
                for s in 1..p {
                    let t = ta + (tb - ta) * s as f64 / p as f64;
                    let node = el[3 + k * (p - 1) + (s - 1)];
                    self.nodes[node] = [
                        center[0] + radius * t.cos(),
                        center[1] + radius * t.sin(),
                        center[2],
                    ];
                }
            }
            if npe == 10 {
                let mut x = [0.0; 3];
                for (j, &node) in el[..9].iter().enumerate() {
                    let w = if j < 3 { -1.0 / 6.0 } else { 0.25 };
                    for i in 0..3 {
                        x[i] += w * self.nodes[node][i];
                    }
                }
                self.nodes[el[9]] = x;
            }
        }
        self
    }
}

/// Raises a linear mesh to `order` by adding edge nodes (shared between
/// neighbours) and, for order 3, an interior node, all on straight lines
/// between the vertices.
pub fn elevate(mesh: &Mesh, order: ElementOrder) -> Mesh {
    let p = order.degree();
    if p == 1 {
        return mesh.clone();
    }
    let mut nodes = mesh.nodes.clone();
    let mut edge_nodes: std::collections::HashMap<(usize, usize), usize> =
        std::collections::HashMap::new();
    let mut connectivity = Vec::with_capacity(mesh.element_count() * order.nodes_per_element());
    let lerp = |a: [f64; 3], b: [f64; 3], s: f64| {
        [
            a[0] + s * (b[0] - a[0]),
            a[1] + s * (b[1] - a[1]),
            a[2] + s * (b[2] - a[2]),
        ]
    };
    for el in mesh.elements() {
        let v = [el[0], el[1], el[2]];
        connectivity.extend_from_slice(&v);
        for k in 0..3 {
            let (a, b) = (v[k], v[(k + 1) % 3]);
            let key = (a.min(b), a.max(b));
            // Edge nodes are created along min -> max and listed from `a`.
            let first = *edge_nodes.entry(key).or_insert_with(|| {
                let start = nodes.len();
                for s in 1..p {
                    nodes.push(lerp(
                        mesh.nodes[key.0],
                        mesh.nodes[key.1],
                        s as f64 / p as f64,
                    ));
                }
                start
            });
            let ids: Vec<usize> = (0..p - 1).map(|s| first + s).collect();
            if a < b {
                connectivity.extend_from_slice(&ids);
            } else {
                connectivity.extend(ids.iter().rev());
            }
        }
        if p == 3 {
            let c = [0, 1, 2]
                .map(|i| (mesh.nodes[v[0]][i] + mesh.nodes[v[1]][i] + mesh.nodes[v[2]][i]) / 3.0);
            connectivity.push(nodes.len());
            nodes.push(c);
        }
    }
    Mesh {
        nodes,
        order,
        connectivity,
    }
}

/// A closed sphere of radius `radius` about `center`: the icosahedron's
/// twenty triangles, each edge cut in two `subdivisions` times (`20 4^s`
/// triangles), every node (the elevated ones too) projected onto the
/// sphere; the triangles' normals (right-hand rule over the node order)
/// point outwards.
pub fn sphere(radius: f64, subdivisions: usize, center: [f64; 3], order: ElementOrder) -> Mesh {
    let t = (1.0 + 5.0f64.sqrt()) / 2.0;
    let mut nodes: Vec<[f64; 3]> = vec![
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ];
    let mut triangles: Vec<[usize; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    let unit = |x: [f64; 3]| {
        let r = (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt();
        [x[0] / r, x[1] / r, x[2] / r]
    };
    for _ in 0..subdivisions {
        let mut middle: std::collections::HashMap<(usize, usize), usize> =
            std::collections::HashMap::new();
        let mut finer = Vec::with_capacity(4 * triangles.len());
        for tri in &triangles {
            let mut mid = |a: usize, b: usize| {
                *middle.entry((a.min(b), a.max(b))).or_insert_with(|| {
                    let (x, y) = (nodes[a], nodes[b]);
                    nodes.push([
                        0.5 * (x[0] + y[0]),
                        0.5 * (x[1] + y[1]),
                        0.5 * (x[2] + y[2]),
                    ]);
                    nodes.len() - 1
                })
            };
            let [a, b, c] = *tri;
            let (ab, bc, ca) = (mid(a, b), mid(b, c), mid(c, a));
            finer.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        triangles = finer;
        for x in nodes.iter_mut() {
            *x = unit(*x);
        }
    }
    let linear = Mesh {
        nodes: nodes.iter().map(|&x| unit(x)).collect(),
        order: ElementOrder::Linear,
        connectivity: triangles.concat(),
    };
    let mut mesh = elevate(&linear, order);
    for x in mesh.nodes.iter_mut() {
        let u = unit(*x);
        *x = [
            center[0] + radius * u[0],
            center[1] + radius * u[1],
            center[2] + radius * u[2],
        ];
    }
    mesh
}

#[cfg(test)]
mod tests {
    use super::*;

    fn total_area(mesh: &Mesh) -> f64 {
        let g = crate::element::ElementGeometry::new(
            mesh,
            &crate::quadrature::QuadratureRule::of_degree(2 * mesh.order.degree()),
        );
        (0..mesh.element_count()).map(|e| g.area(e)).sum()
    }

    #[test]
    fn rectangles_are_valid_and_have_the_right_area_and_counts() {
        for order in [
            ElementOrder::Linear,
            ElementOrder::Quadratic,
            ElementOrder::Cubic,
        ] {
            for pattern in [Pattern::Right, Pattern::Left, Pattern::Alternate] {
                let m = rectangle([0.2, 0.3], [4, 6], pattern, [1.0, 2.0, 3.0], order);
                m.validate().unwrap();
                let p = order.degree();
                assert_eq!(m.node_count(), (4 * p + 1) * (6 * p + 1));
                assert_eq!(m.element_count(), 48);
                assert!((total_area(&m) - 0.06).abs() < 1e-14);
                assert_eq!(m.boundary_nodes().len(), 2 * (4 * p + 6 * p));
            }
        }
    }

    #[test]
    fn discs_are_valid_and_converge_to_the_circle_area() {
        let exact = std::f64::consts::PI * 0.15f64.powi(2);
        let mut previous = f64::INFINITY;
        for order in [
            ElementOrder::Linear,
            ElementOrder::Quadratic,
            ElementOrder::Cubic,
        ] {
            let m = disc(0.15, 5, [0.0; 3], order);
            m.validate().unwrap();
            assert_eq!(m.element_count(), 6 * 25);
            let error = (total_area(&m) - exact).abs() / exact;
            assert!(error < previous, "{order:?}: {error}");
            previous = error;
        }
        // Curved rims: the quadratic disc is much closer to the circle.
        assert!(previous < 1e-4);
    }
}
