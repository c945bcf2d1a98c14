//! Helpers shared by the fuzz targets.

use drape::contact::Obstacle;
use drape::contact::obstacle::TriMeshObstacle;
use drape::mesh::Mesh;

/// Builds the obstacle `read_mesh_obstacle` would build from `mesh` and,
/// if it is accepted, queries it as a contact search does: closest points
/// of points on, inside, near and far from it, with and without hints
/// (valid, stale and out-of-range features).
pub fn obstacle_from(name: &str, mesh: Mesh) {
    let triangles = mesh
        .elements()
        .filter_map(|e| <[usize; 3]>::try_from(e.get(..3)?).ok())
        .collect();
    let Ok(obstacle) = TriMeshObstacle::new(name, mesh.nodes, triangles) else {
        return;
    };
    let _ = obstacle.describe();
    let (lo, hi) = obstacle.bounding_box();
    let centre = [0, 1, 2].map(|k| 0.5 * lo[k] + 0.5 * hi[k]);
    let far = [0, 1, 2].map(|k| hi[k] + (hi[k] - lo[k]));
    let mut points = vec![centre, lo, hi, far];
    for (t, tri) in obstacle.triangles().iter().enumerate().take(16) {
        let [a, b, c] = tri.map(|v| obstacle.vertices()[v]);
        let g = [0, 1, 2].map(|k| (a[k] + b[k] + c[k]) / 3.0);
        let n = obstacle.triangle_normal(t).unwrap_or([0.0; 3]);
        let h = 1e-3 * (hi[0] - lo[0]).abs().max(1e-300);
        points.extend([
            a,
            g,
            [0, 1, 2].map(|k| g[k] + h * n[k]),
            [0, 1, 2].map(|k| g[k] - h * n[k]),
        ]);
    }
    let last = obstacle.triangles().len().saturating_sub(1) as u32;
    let mut hint = None;
    for p in points {
        for h in [None, Some(0), Some(last), Some(u32::MAX), hint] {
            let q = obstacle.proximity(p, h);
            hint = Some(q.feature);
            let _ = obstacle.constraint(p, q.feature);
        }
    }
}
