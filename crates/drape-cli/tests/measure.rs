//! `drape measure` (README, "Measuring a drape"; issue 22) on the outputs of real runs and of
//! a frame written by hand: the JSON object's keys and values, the frame
//! chosen, and the bad inputs — no outputs, a step not written, no disc on
//! a cylinder, a radius that cannot be — each refused with exit status 2
//! and a message that names the path, the step or the value.

use drape::output::pvd::{PvdWriter, frame_relative_path};
use drape::output::vtu::{DataArray, Frame, Values, write_vtu};
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Keys of the JSON object, in their order (README "Measuring a drape").
const KEYS: [&str; 14] = [
    "step",
    "time",
    "shadow_area",
    "drape_coefficient",
    "folds",
    "pedestal_radius",
    "specimen_radius",
    "shadow_area_error_bound",
    "pedestal_radius_from",
    "specimen_radius_from",
    "vertical",
    "center",
    "frame",
    "crossings",
];

fn drape(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_drape"))
        .args(args)
        .output()
        .unwrap()
}

/// A fresh directory for one test, under the system's temporary one.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("drape-measure-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn example(name: &str) -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("../../examples/{name}.toml"));
    std::fs::read_to_string(path).unwrap()
}

/// `text` cut to 3 fixed steps of 1 ms (the drape tester's skirt has
/// barely started to drop), a frame each.
fn three_steps(text: &str) -> String {
    text.lines()
        .filter(|l| {
            !["adaptive", "dt_max", "rest ="]
                .iter()
                .any(|k| l.starts_with(k))
        })
        .map(|l| {
            if l.starts_with("segments") {
                "segments = [ { steps = 3, dt = 1.0e-3 } ]".to_owned()
            } else if l.starts_with("every =") {
                "every = 1".to_owned()
            } else {
                l.to_owned()
            }
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// Runs `text` into `dir/out`.
fn run(dir: &Path, text: &str) -> PathBuf {
    let scenario = dir.join("scenario-in.toml");
    std::fs::write(&scenario, text).unwrap();
    let out = dir.join("out");
    let o = drape(&[
        "run",
        scenario.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "-q",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    out
}

/// `drape measure` that succeeds: its JSON object, checked for the keys.
fn measured(args: &[&str]) -> Value {
    let o = drape(&[&["measure"], args].concat());
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8(o.stdout).unwrap();
    assert_eq!(text.lines().count(), 1, "one line: {text}");
    let v: Value = serde_json::from_str(&text).unwrap();
    assert_eq!(v.as_object().unwrap().len(), KEYS.len(), "{text}");
    let at: Vec<usize> = KEYS
        .iter()
        .map(|k| {
            text.find(&format!("\"{k}\":"))
                .unwrap_or_else(|| panic!("no {k}: {text}"))
        })
        .collect();
    assert!(
        at.windows(2).all(|w| w[0] < w[1]),
        "keys out of order: {text}"
    );
    v
}

/// `drape measure` that is refused as bad input: its message.
fn refused(args: &[&str]) -> String {
    let o = drape(&[&["measure"], args].concat());
    assert_eq!(
        o.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(o.stdout.is_empty());
    String::from_utf8(o.stderr).unwrap()
}

/// The drape tester without its top disc (whose shading, drawn over the
/// fabric's centre in the top view, has pixels of the specimen circle's
/// grey); the measurement is the same with it (tests/measure.rs).
fn without_top_disc(text: &str) -> String {
    let start = text
        .find("[[obstacle]]                 # the top disc")
        .expect("a top disc");
    let end = start + text[start..].find("\n\n").expect("a blank line after it") + 2;
    format!("{}{}", &text[..start], &text[end..])
}

#[test]
fn drape_tester_frames_are_measured() {
    let dir = scratch("tester");
    let out = run(
        &dir,
        &three_steps(&without_top_disc(&example("drape-tester"))),
    );
    let out_s = out.to_str().unwrap();
    // Step 0: the flat disc, DC = 1 within 0.5 % (the 90-gon inscribed in
    // the circle: 1 − 0.13 %).
    let v = measured(&[out_s, "--step", "0"]);
    assert_eq!(v["step"], 0);
    assert_eq!(v["time"], 0.0);
    let dc = v["drape_coefficient"].as_f64().unwrap();
    assert!((dc - 1.0).abs() < 0.005, "{dc}");
    assert_eq!(v["folds"], 0);
    assert_eq!(v["pedestal_radius"], 0.09);
    assert_eq!(v["specimen_radius"], 0.15);
    assert_eq!(v["pedestal_radius_from"], "obstacle[0]");
    assert_eq!(v["specimen_radius_from"], "mesh.radius");
    assert_eq!(v["vertical"], serde_json::json!([0.0, 0.0, 1.0]));
    let area = v["shadow_area"].as_f64().unwrap();
    let polygon = 45.0 * 0.15f64.powi(2) * (std::f64::consts::TAU / 90.0).sin();
    assert!((area - polygon).abs() < 1e-14, "{area} vs {polygon}");
    assert!(v["frame"].as_str().unwrap().ends_with("step_000000.vtu"));
    // The last frame by default; the nearest by time.
    assert_eq!(measured(&[out_s])["step"], 3);
    assert_eq!(measured(&[out_s, "--time", "0.0011"])["step"], 1);
    // A radius given takes the place of the one found.
    let v = measured(&[out_s, "--step", "0", "--pedestal-radius", "0.05"]);
    assert_eq!(v["pedestal_radius"], 0.05);
    assert_eq!(v["pedestal_radius_from"], "given");
    let pi = std::f64::consts::PI;
    let dc = (area - pi * 0.05 * 0.05) / (pi * (0.15 * 0.15 - 0.05 * 0.05));
    assert!((v["drape_coefficient"].as_f64().unwrap() - dc).abs() < 1e-12);

    // A step that was not written names the step and the collection.
    let e = refused(&[out_s, "--step", "7"]);
    assert!(
        e.contains("step 7 was not written") && e.contains("fields.pvd"),
        "{e}"
    );
    // Radii that cannot be name their values.
    let e = refused(&[out_s, "--pedestal-radius", "0.2"]);
    assert!(e.contains("0.2") && e.contains("not smaller"), "{e}");
    let e = refused(&[out_s, "--specimen-radius=-1"]);
    assert!(e.contains("specimen radius -1"), "{e}");
    // --step and --time together.
    refused(&[out_s, "--step", "0", "--time", "0"]);

    // `drape plot` adds the drape coefficient and the folds: two more
    // panels, a taller figure.
    let o = drape(&["plot", out_s]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(!String::from_utf8_lossy(&o.stderr).contains("note:"));
    let png = drape_render::RgbImage::read_png(&out.join("plot.png")).unwrap();
    assert_eq!((png.width, png.height), (1200, 1200));
    // A drape tester whose pedestal cannot be told (a second cylinder, its
    // top at the same height): the panels are left out, and a note says
    // why (issue 35: they were dropped without a word).
    let kept = std::fs::read_to_string(out.join("scenario.toml")).unwrap();
    std::fs::write(
        out.join("scenario.toml"),
        format!(
            "{kept}\n[[obstacle]]\nshape = \"cylinder\"\ncenter = [0.0, 0.0, 2.0e-6]\naxis = [0.0, 0.0, 1.0]\nradius = 0.12\nheight = 0.1\n"
        ),
    )
    .unwrap();
    let o = drape(&["plot", out_s]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{e}");
    assert!(
        e.contains("note: no drape coefficient or folds panels")
            && e.contains("tops at one height")
            && e.contains("--pedestal-radius"),
        "{e}"
    );
    let png = drape_render::RgbImage::read_png(&out.join("plot.png")).unwrap();
    assert_eq!((png.width, png.height), (1200, 900));
    std::fs::write(out.join("scenario.toml"), kept).unwrap();
    // `drape render --view top` draws the pedestal (solid, [20, 20, 20])
    // and the specimen's circle (dashed, [90, 90, 90]) over the fabric: the
    // pixels of those colours in the picture (below the title, left of the
    // colour bar) lie on two rings about one centre, radii in the ratio
    // r_p / R = 0.6.
    let png = dir.join("top.png");
    let o = drape(&[
        "render",
        out_s,
        "--view",
        "top",
        "--step",
        "0",
        "-o",
        png.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let img = drape_render::RgbImage::read_png(&png).unwrap();
    let ring = |colour: [u8; 3]| -> (f64, f64) {
        let pixels: Vec<(f64, f64)> = (100..img.height)
            .flat_map(|y| (0..960).map(move |x| (x, y)))
            .filter(|&(x, y)| img.get(x, y) == Some(colour))
            .map(|(x, y)| (x as f64 + 0.5, y as f64 + 0.5))
            .collect();
        assert!(pixels.len() > 200, "{} pixels of {colour:?}", pixels.len());
        let n = pixels.len() as f64;
        let c = pixels
            .iter()
            .fold((0.0, 0.0), |s, p| (s.0 + p.0 / n, s.1 + p.1 / n));
        let r: Vec<f64> = pixels
            .iter()
            .map(|p| (p.0 - c.0).hypot(p.1 - c.1))
            .collect();
        let (lo, hi) = (
            r.iter().copied().fold(f64::INFINITY, f64::min),
            r.iter().copied().fold(0.0, f64::max),
        );
        // A ring of a line 3 px wide.
        assert!(hi - lo < 4.0, "{colour:?}: radii {lo} to {hi}");
        (0.5 * (lo + hi), c.0.hypot(c.1))
    };
    let (pedestal, pc) = ring([20, 20, 20]);
    let (specimen, sc) = ring([90, 90, 90]);
    assert!((pc - sc).abs() < 2.0);
    assert!(
        (pedestal / specimen - 0.6).abs() < 0.01,
        "{pedestal} / {specimen}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_directory_without_outputs_is_refused() {
    let dir = scratch("empty");
    let e = refused(&[dir.to_str().unwrap()]);
    assert!(
        e.contains(&format!("{}", dir.join("fields.pvd").display())),
        "{e}"
    );
    let missing = dir.join("nowhere");
    let e = refused(&[missing.to_str().unwrap()]);
    assert!(e.contains("nowhere") && e.contains("does not exist"), "{e}");
    // A collection that lists no frame.
    std::fs::write(
        dir.join("fields.pvd"),
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\"><Collection>\n</Collection></VTKFile>\n",
    )
    .unwrap();
    let e = refused(&[dir.to_str().unwrap()]);
    assert!(e.contains("no frames"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The square fabric on a box (fabric-on-pedestal.toml): no disc, no
/// cylinder; measured once both radii are given.
#[test]
fn a_scenario_that_is_not_a_disc_on_a_cylinder_needs_the_radii() {
    let dir = scratch("square");
    let out = run(&dir, &three_steps(&example("fabric-on-pedestal")));
    let out_s = out.to_str().unwrap();
    let scenario = out.join("scenario.toml");
    // Not a drape tester: the plot is the history's alone, without a word.
    let o = drape(&["plot", out_s]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(!String::from_utf8_lossy(&o.stderr).contains("note:"));
    let png = drape_render::RgbImage::read_png(&out.join("plot.png")).unwrap();
    assert_eq!((png.width, png.height), (1200, 900));
    let e = refused(&[out_s]);
    assert!(
        e.contains(&scenario.display().to_string())
            && e.contains("cylinder")
            && e.contains("--pedestal-radius"),
        "{e}"
    );
    let e = refused(&[out_s, "--pedestal-radius", "0.05"]);
    assert!(
        e.contains(&scenario.display().to_string())
            && e.contains("rectangle")
            && e.contains("--specimen-radius"),
        "{e}"
    );
    let v = measured(&[
        out_s,
        "--step",
        "0",
        "--pedestal-radius",
        "0.05",
        "--specimen-radius",
        "0.1",
    ]);
    // The flat 0.2 m square: its shadow is its area.
    assert!((v["shadow_area"].as_f64().unwrap() - 0.04).abs() < 1e-14);
    // Without the scenario at all, the radii are all it takes.
    std::fs::remove_file(&scenario).unwrap();
    let e = refused(&[out_s]);
    assert!(e.contains("(not found)"), "{e}");
    measured(&[
        out_s,
        "--pedestal-radius",
        "0.05",
        "--specimen-radius",
        "0.1",
    ]);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Writes the frame of `mesh` at `positions` as step `step` at time `time`
/// (s) into `dir`, the collection `fields.pvd` listing it alone.
fn frame_by_hand(
    dir: &Path,
    mesh: &drape::mesh::Mesh,
    positions: &[[f64; 3]],
    step: u64,
    time: f64,
) {
    let displacement: Vec<f64> = positions
        .iter()
        .zip(&mesh.nodes)
        .flat_map(|(y, x)| [y[0] - x[0], y[1] - x[1], y[2] - x[2]])
        .collect();
    let rel = frame_relative_path(step);
    std::fs::create_dir_all(dir.join("fields")).unwrap();
    let frame = Frame {
        positions,
        connectivity: &mesh.connectivity,
        nodes_per_element: 3,
        point_data: vec![DataArray {
            name: "displacement",
            components: 3,
            values: Values::F64(&displacement),
            component_names: &[],
        }],
        cell_data: vec![],
        time,
    };
    write_vtu(&dir.join(&rel), &frame).unwrap();
    PvdWriter::new(dir.join("fields.pvd"))
        .push(time, &rel)
        .unwrap();
}

/// A frame written by hand next to the drape tester's scenario: the disc
/// hanging straight down round the pedestal, DC near 0.
#[test]
fn a_disc_hanging_straight_down_measures_dc_near_zero() {
    let dir = scratch("hanging");
    std::fs::write(dir.join("scenario.toml"), example("drape-tester")).unwrap();
    let (r_p, radius, rings) = (0.09, 0.15, 15);
    let mesh =
        drape::mesh::generate::disc(radius, rings, [0.0; 3], drape::mesh::ElementOrder::Linear);
    let hanging: Vec<[f64; 3]> = mesh
        .nodes
        .iter()
        .map(|&x| {
            let r = x[0].hypot(x[1]);
            if r <= r_p + 1e-12 {
                x
            } else {
                let t = x[1].atan2(x[0]);
                [r_p * t.cos(), r_p * t.sin(), -(r - r_p)]
            }
        })
        .collect();
    frame_by_hand(&dir, &mesh, &hanging, 40, 2.5);
    let v = measured(&[dir.to_str().unwrap()]);
    assert_eq!(v["step"], 40);
    assert_eq!(v["time"], 2.5);
    let dc = v["drape_coefficient"].as_f64().unwrap();
    // Between the pedestal's inscribed 54-gon (−0.13 %) and its circle (0).
    assert!((-0.002..=0.0).contains(&dc), "{dc}");
    assert_eq!(v["folds"], 0);
    let _ = std::fs::remove_dir_all(&dir);
}

/// The flat disc of the drape tester (15 rings) written by hand as step 0
/// next to `scenario`, measured: its JSON object.
fn flat_disc_measured(name: &str, scenario: &str) -> Value {
    let dir = scratch(name);
    std::fs::write(dir.join("scenario.toml"), scenario).unwrap();
    let mesh = drape::mesh::generate::disc(0.15, 15, [0.0; 3], drape::mesh::ElementOrder::Linear);
    frame_by_hand(&dir, &mesh, &mesh.nodes, 0, 0.0);
    let v = measured(&[dir.to_str().unwrap()]);
    let _ = std::fs::remove_dir_all(&dir);
    v
}

/// The numbers of a JSON array.
fn floats(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|c| c.as_f64().unwrap())
        .collect()
}

/// The DC of the flat disc of 15 rings (the inscribed 90-gon) on a
/// pedestal of radius `r_p`, projected along a vertical tilted by `tilt`
/// (rad) from its normal.
fn flat_dc(r_p: f64, tilt: f64) -> f64 {
    let pi = std::f64::consts::PI;
    let area = 45.0 * 0.15f64.powi(2) * (std::f64::consts::TAU / 90.0).sin() * tilt.cos();
    (area - pi * r_p * r_p) / (pi * (0.15f64.powi(2) - r_p * r_p))
}

/// Issue 46: a second surface load of 1e-6 N/m² sideways beside the
/// drape tester's weight of 1.8816 N/m² tilts the vertical by
/// 1e-6 / 1.8816 rad, and the flat disc measures DC 1 less its polygon's
/// shortfall, 0 folds (the vertical was [−0.707, 0, 0.707]: refused for
/// want of an axial cylinder, and with both radii given DC 0.524 and 2
/// folds on a 45° plane). Loads that cancel are refused, naming the
/// scenario.
#[test]
fn a_negligible_sideways_load_does_not_tilt_the_vertical() {
    let weight = "[[load]]\nkind = \"surface\"\nforce = [0.0, 0.0, -1.8816]\n";
    let text = example("drape-tester");
    assert!(text.contains(weight));
    let nudged = text.replace(
        weight,
        &format!("{weight}\n[[load]]\nkind = \"surface\"\nforce = [1.0e-6, 0.0, 0.0]\n"),
    );
    let v = flat_disc_measured("nudged", &nudged);
    let k = floats(&v["vertical"]);
    let n = 1e-6f64.hypot(1.8816);
    // A few roundings of unit components.
    assert!(
        (k[0] + 1e-6 / n).abs() < 1e-15 && k[1] == 0.0 && (k[2] - 1.8816 / n).abs() < 1e-15,
        "{k:?}"
    );
    assert_eq!(v["pedestal_radius_from"], "obstacle[0]");
    let dc = v["drape_coefficient"].as_f64().unwrap();
    // Rounding of the area (~1e-17 m²) over π (R² − r_p²).
    let expected = flat_dc(0.09, (1e-6f64 / 1.8816).atan());
    assert!((dc - expected).abs() < 1e-13, "{dc} vs {expected}");
    assert_eq!(v["folds"], 0);
    // A lift that cancels the weight, beside the nudge: no way down.
    let cancelled = nudged.replace(
        weight,
        &format!("{weight}\n[[load]]\nkind = \"surface\"\nforce = [0.0, 0.0, 1.8816]\n"),
    );
    let dir = scratch("cancelled");
    std::fs::write(dir.join("scenario.toml"), &cancelled).unwrap();
    let mesh = drape::mesh::generate::disc(0.15, 15, [0.0; 3], drape::mesh::ElementOrder::Linear);
    frame_by_hand(&dir, &mesh, &mesh.nodes, 0, 0.0);
    let e = refused(&[dir.to_str().unwrap()]);
    assert!(
        e.contains("scenario.toml") && e.contains("no vertical") && e.contains("cancel"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Issue 46: the drape tester's 9 cm pedestal given with its axis down
/// (`center` at its bottom face, 20 cm under the specimen; its top face
/// `center − height · axis` at the specimen) over a 12 cm stand whose top
/// is 10 cm under the specimen: the pedestal is measured on, not the
/// stand (r_p was 0.12, DC 0.955 instead of 0.975), about the centre of
/// its top face.
#[test]
fn a_pedestal_given_axis_down_is_ranked_by_its_top_face() {
    let pedestal = "center = [0.0, 0.0, 2.0e-6]   # centre of the top face: 2 um into the specimen\naxis = [0.0, 0.0, 1.0]\nradius = 0.09\nheight = 0.2\n";
    let text = without_top_disc(&example("drape-tester"));
    assert!(text.contains(pedestal));
    let flipped = text.replace(
        pedestal,
        "center = [0.0, 0.0, -0.199998]\naxis = [0.0, 0.0, -1.0]\nradius = 0.09\nheight = 0.2\n\n\
         [[obstacle]]\nshape = \"cylinder\"\ncenter = [0.0, 0.0, -0.1]\naxis = [0.0, 0.0, 1.0]\nradius = 0.12\nheight = 0.1\n",
    );
    let v = flat_disc_measured("flipped", &flipped);
    assert_eq!(v["pedestal_radius"], 0.09);
    assert_eq!(v["pedestal_radius_from"], "obstacle[0]");
    let c = floats(&v["center"]);
    // −0.199998 + 0.2, to rounding.
    assert!(
        c[0] == 0.0 && c[1] == 0.0 && (c[2] - 2e-6).abs() < 1e-16,
        "{c:?}"
    );
    let dc = v["drape_coefficient"].as_f64().unwrap();
    assert!((dc - flat_dc(0.09, 0.0)).abs() < 1e-13, "{dc}");
}
