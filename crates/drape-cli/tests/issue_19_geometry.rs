//! Issue 19: geometry that was silently wrong. An obstacle that moves
//! more than half the fabric's smallest element edge in one step (it can
//! pass through the fabric between two steps unseen) is warned about by
//! `check` and `run`, and the warning is recorded in `summary.json`.

mod issue_19_support;

use issue_19_support::{drape, falling_plate, run_into, scratch, text};
use serde_json::Value;

/// A sphere above the 4 x 4 plate (edges of 2.5 cm) falling at `speed`
/// m/s, steps of 1 ms.
fn sphere(speed: f64) -> String {
    format!(
        "[[obstacle]]\nshape = \"sphere\"\ncenter = [0.05, 0.05, 0.5]\nradius = 0.05\nvelocity = [0.0, 0.0, {}]\n[contact]\nmethod = \"penalty\"\npenalty = 1.0e4",
        -speed
    )
}

#[test]
fn an_obstacle_faster_than_the_mesh_is_warned_about_and_recorded() {
    let dir = scratch("geometry-fast");
    // 1000 m/s x 1 ms = 1 m a step against 0.5 x 0.025 m.
    let scenario = falling_plate(&dir, 3, &sphere(1000.0));
    let o = drape(&["check".as_ref(), scenario.as_os_str()]);
    let said = text(&o.stdout);
    assert!(o.status.success(), "{}", text(&o.stderr));
    for f in [
        "warning",
        "obstacle[0] moves 1.000e0 m in a step",
        "2.500e-2 m",
        "pass through the fabric",
    ] {
        assert!(said.contains(f), "expected {f:?} in {said}");
    }
    let out = dir.join("out");
    let o = run_into(&scenario, &out);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(text(&o.stderr).contains("warning: obstacle[0] moves"));
    let s: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let warnings = s["warnings"].as_array().expect("warnings in the summary");
    assert_eq!(warnings.len(), 1, "{s}");
    assert!(warnings[0].as_str().unwrap().contains("obstacle[0] moves"));

    // 10 m/s: 1 cm a step, below 1.25 cm: no warning, no key.
    let slow = falling_plate(&dir, 3, &sphere(10.0));
    let o = drape(&["check".as_ref(), slow.as_os_str()]);
    assert!(!text(&o.stdout).contains("warning"), "{}", text(&o.stdout));
    let o = run_into(&slow, &out);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let s: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert!(s.get("warnings").is_none(), "{s}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `dir/fall.toml` on the OBJ mesh `obj` (its text), written as `name`.
fn on_obj(dir: &std::path::Path, name: &str, obj: &str) -> std::path::PathBuf {
    std::fs::write(dir.join(name), obj).unwrap();
    let scenario = falling_plate(dir, 2, "");
    let text = std::fs::read_to_string(&scenario).unwrap().replace(
        "shape = \"rectangle\"\nsize = [0.1, 0.1]\ndivisions = [4, 4]",
        &format!("shape = \"file\"\npath = \"{name}\""),
    );
    std::fs::write(&scenario, text).unwrap();
    scenario
}

/// An L-shaped hexagon written from a corner that does not see the whole
/// face (a fan from it folds a triangle over): cut into ears, its mass is
/// that of its area, 0.03 m^2 x 0.6 mm x 320 kg/m^3 = 5.76e-3 kg. A bent
/// quad and a bow tie are refused naming the face and its line.
#[test]
fn obj_polygons_are_cut_into_ears_or_refused_by_face() {
    let dir = scratch("geometry-polygons");
    let l = "v 0 0 0\nv 0.2 0 0\nv 0.2 0.1 0\nv 0.1 0.1 0\nv 0.1 0.2 0\nv 0 0.2 0\nf 6 1 2 3 4 5\n";
    let o = drape(&["check".as_ref(), on_obj(&dir, "l.obj", l).as_os_str()]);
    let said = text(&o.stdout);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(said.contains("6 nodes, 4 triangles"), "{said}");
    assert!(said.contains("mass      5.760000e-3 kg"), "{said}");

    for (name, obj, fragments) in [
        (
            "bent.obj",
            "v 0 0 0\nv 0.1 0 0\nv 0.1 0.1 0.01\nv 0 0.1 0\nf 1 2 3\nf 1 2 3 4\n",
            &[
                "bent.obj",
                "line 6",
                "face 2 (4 corners): it is not planar",
                "off its plane",
            ][..],
        ),
        (
            "bow.obj",
            "v 0 0 0\nv 0.2 0.2 0\nv 0.2 0 0\nv 0 0.1 0\nf 1 2 3 4\n",
            &[
                "bow.obj",
                "line 5",
                "face 1 (4 corners): it intersects itself",
            ][..],
        ),
    ] {
        let o = drape(&["check".as_ref(), on_obj(&dir, name, obj).as_os_str()]);
        let e = text(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{e}");
        for f in fragments {
            assert!(e.contains(f), "expected {f:?} in {e}");
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}
