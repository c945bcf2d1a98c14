//! The self-contact broad phase against the mesh size (issue 33): `cargo
//! run --release -p drape-bench --example self_proximity` builds two wavy
//! square plies of `n x n` squares each, 1 cm apart (their waves bring
//! them to 0.02 mm), and times `drape::contact::proximity::close_pairs` (the
//! spatial-hash broad phase and the exact distances) for a distance of a
//! quarter of the squares' side (a barrier's reach is a fraction of the
//! element size), at n = 32 to 256 (4,096 to 262,144 triangles); the best
//! of three runs each, and the time per thousand triangles.

use drape::contact::proximity::{close_pairs, edges_of};
use std::time::Instant;

fn plies(n: usize) -> (Vec<[f64; 3]>, Vec<[usize; 3]>) {
    let (mut x, mut triangles) = (Vec::new(), Vec::new());
    for ply in 0..2 {
        let base = x.len();
        let sign = if ply == 0 { 1.0 } else { -1.0 };
        for j in 0..=n {
            for i in 0..=n {
                let (u, v) = (i as f64 / n as f64 * 0.2, j as f64 / n as f64 * 0.2);
                let z = 0.01 * ply as f64 + sign * 0.00499 * (30.0 * u).sin() * (20.0 * v).cos();
                x.push([u, v, z]);
            }
        }
        for j in 0..n {
            for i in 0..n {
                let a = base + j * (n + 1) + i;
                triangles.push([a, a + 1, a + n + 2]);
                triangles.push([a, a + n + 2, a + n + 1]);
            }
        }
    }
    (x, triangles)
}

fn main() {
    println!(
        "triangles  distance (mm)  node-triangle pairs  edge-edge pairs  time (ms)  ms per 1k triangles"
    );
    for n in [32, 64, 128, 256] {
        let (x, triangles) = plies(n);
        let edges = edges_of(&triangles);
        let distance = 0.25 * 0.2 / n as f64;
        let mut best = f64::INFINITY;
        let mut pairs = None;
        for _ in 0..3 {
            let start = Instant::now();
            let found = close_pairs(&x, &triangles, &edges, distance);
            best = best.min(start.elapsed().as_secs_f64() * 1e3);
            pairs = Some(found);
        }
        let pairs = pairs.expect("three runs");
        println!(
            "{:>9}  {:>13.3}  {:>19}  {:>15}  {:>9.1}  {:>19.3}",
            triangles.len(),
            distance * 1e3,
            pairs.point_triangle.len(),
            pairs.edge_edge.len(),
            best,
            best / (triangles.len() as f64 / 1e3)
        );
    }
}
