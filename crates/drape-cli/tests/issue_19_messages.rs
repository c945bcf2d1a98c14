//! Issue 19: messages that misled now say what is wrong, and `plot`,
//! `render` and `measure` refuse (exit 2) what they cannot interpret rather
//! than draw empty panels or a blank image, or measure nonsense. (The scenario's messages — a modulus of
//! 1e308, a size of 1e200, a centre at 1e17 m, a node at 1e300 m,
//! `[[mesh]]`, a date-time, a schedule that overflows — are cases of the
//! bad-input catalogue in cli.rs.)

mod issue_19_support;

use issue_19_support::{DRAPE, drape, falling_plate, run_into, scratch, text};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// The plate of [`falling_plate`] with a monitor at its corner.
fn scenario(dir: &Path, steps: usize) -> PathBuf {
    falling_plate(
        dir,
        steps,
        "[[monitor]]\nname = \"corner\"\nat = [0.05, 0.05, 0.0]",
    )
}

/// A run of `steps` steps of [`scenario`] into `dir/out`.
fn run(dir: &Path, steps: usize) -> PathBuf {
    let scenario = scenario(dir, steps);
    let out = dir.join("out");
    let o = run_into(&scenario, &out);
    assert!(o.status.success(), "{}", text(&o.stderr));
    out
}

/// Exit 2, stderr holding every fragment, no image written.
fn refused(args: &[&std::ffi::OsStr], image: &Path, fragments: &[&str]) {
    let o = drape(args);
    let e = text(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{args:?}: {e}");
    for f in fragments {
        assert!(e.contains(f), "{args:?}: expected {f:?} in {e}");
    }
    assert!(!e.contains("panicked"), "{e}");
    assert!(!image.exists(), "{args:?} wrote {}", image.display());
}

/// `check` says "1 step", not "1 steps".
#[test]
fn check_counts_one_step_in_the_singular() {
    let dir = scratch("msg-one-step");
    let o = drape(&["check".as_ref(), scenario(&dir, 1).as_os_str()]);
    let out = text(&o.stdout);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(out.contains(", 1 step to t = 0.001 s"), "{out}");
    let o = drape(&["check".as_ref(), scenario(&dir, 2).as_os_str()]);
    assert!(text(&o.stdout).contains(", 2 steps to t = 0.002 s"));
    let _ = std::fs::remove_dir_all(&dir);
}

/// A history without its columns, or without a monitor its scenario
/// names, is refused by plot naming what is missing (it drew panels
/// saying "no [[monitor]] in the scenario", exit 0).
#[test]
fn plot_refuses_a_history_it_cannot_interpret() {
    let dir = scratch("msg-plot");
    let out = run(&dir, 3);
    let png = dir.join("plot.png");
    let args = [
        "plot".as_ref(),
        out.as_os_str(),
        "-o".as_ref(),
        png.as_os_str(),
    ];
    let history = std::fs::read_to_string(out.join("history.csv")).unwrap();
    // The first four columns only.
    let cut: String = history
        .lines()
        .map(|l| l.split(',').take(4).collect::<Vec<_>>().join(",") + "\n")
        .collect();
    std::fs::write(out.join("history.csv"), cut).unwrap();
    refused(
        &args,
        &png,
        &[
            "history.csv",
            "lacks the column(s) kinetic_energy, strain_energy",
        ],
    );
    // Every column but the monitor's.
    let header: Vec<&str> = history.lines().next().unwrap().split(',').collect();
    let keep: Vec<usize> = (0..header.len())
        .filter(|&i| !header[i].starts_with("corner_"))
        .collect();
    let cut: String = history
        .lines()
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            keep.iter().map(|&i| f[i]).collect::<Vec<_>>().join(",") + "\n"
        })
        .collect();
    std::fs::write(out.join("history.csv"), cut).unwrap();
    refused(
        &args,
        &png,
        &["lacks the column(s) corner_x, corner_y, corner_z"],
    );
    // The history as written plots.
    std::fs::write(out.join("history.csv"), history).unwrap();
    let o = drape(&args);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(png.is_file());
    let _ = std::fs::remove_dir_all(&dir);
}

/// What to damage in a frame: `"points"` or an array, the index of the
/// value (in the flattened positions or the array), the value to put.
type Damage<'a> = (&'a str, usize, f64);

/// `frame` rewritten as the 4 x 4 plate's 25 points and 32 triangles at
/// rest, its point arrays `displacement` and `velocity` and its cell array
/// `stress` zero, then each value `damage` names — the point (`"points"`)
/// or the array, the value's index, the value — set.
fn write_damaged_frame(frame: &Path, damage: Damage) {
    use drape::output::vtu::{DataArray, Frame, Values, write_vtu};
    let mut positions: Vec<[f64; 3]> = (0..25)
        .map(|k| [0.025 * (k % 5) as f64, 0.025 * (k / 5) as f64, 0.0])
        .collect();
    let connectivity: Vec<usize> = (0..4)
        .flat_map(|j| (0..4).map(move |i| (i, j)))
        .flat_map(|(i, j)| {
            let n = |i: usize, j: usize| 5 * j + i;
            [
                n(i, j),
                n(i + 1, j),
                n(i + 1, j + 1),
                n(i, j),
                n(i + 1, j + 1),
                n(i, j + 1),
            ]
        })
        .collect();
    let (mut displacement, mut velocity, mut stress) =
        (vec![0.0; 75], vec![0.0; 75], vec![0.0; 96]);
    let (what, at, value) = damage;
    match what {
        "points" => positions[at / 3][at % 3] = value,
        "displacement" => displacement[at] = value,
        "velocity" => velocity[at] = value,
        "stress" => stress[at] = value,
        _ => unreachable!("{what}"),
    }
    let array = |name, components, values| DataArray {
        name,
        components,
        values: Values::F64(values),
        component_names: &[],
    };
    write_vtu(
        frame,
        &Frame {
            positions: &positions,
            connectivity: &connectivity,
            nodes_per_element: 3,
            point_data: vec![
                array("displacement", 3, &displacement),
                array("velocity", 3, &velocity),
            ],
            cell_data: vec![array("stress", 3, &stress)],
            time: 0.003,
        },
    )
    .unwrap();
}

/// The last frame rewritten with a value that is not finite — a point's
/// position, a point array's value, a cell array's value: `render` refuses
/// it naming the frame, the array and the first node or cell (with a NaN
/// point it drew a blank image, exit 0; a NaN velocity or an infinite
/// stress was drawn), and `measure` refuses it likewise (it measured).
#[test]
fn render_and_measure_refuse_a_frame_that_is_not_finite() {
    let dir = scratch("msg-nan");
    let out = run(&dir, 3);
    let frame = out.join("fields/step_000003.vtu");
    assert!(frame.is_file());
    let png = dir.join("render.png");
    let render: [&std::ffi::OsStr; 4] = [
        "render".as_ref(),
        out.as_os_str(),
        "-o".as_ref(),
        png.as_os_str(),
    ];
    let measure: [&std::ffi::OsStr; 6] = [
        "measure".as_ref(),
        out.as_os_str(),
        "--pedestal-radius".as_ref(),
        "0.02".as_ref(),
        "--specimen-radius".as_ref(),
        "0.05".as_ref(),
    ];
    let cases: [(Damage, &[&str]); 4] = [
        (
            ("points", 3 * 7, f64::NAN),
            &["point 7", "no finite position"],
        ),
        (
            ("displacement", 3 * 12 + 2, f64::INFINITY),
            &[
                "point array \"displacement\" holds inf at node 12",
                "component 2",
            ],
        ),
        (
            ("velocity", 3 * 3 + 1, f64::NAN),
            &[
                "point array \"velocity\" holds NaN at node 3",
                "component 1",
            ],
        ),
        (
            ("stress", 3 * 5 + 2, f64::NEG_INFINITY),
            &["cell array \"stress\" holds -inf at cell 5", "component 2"],
        ),
    ];
    for (damage, said) in cases {
        write_damaged_frame(&frame, damage);
        let fragments = [&["step_000003.vtu", "the frame is damaged"], said].concat();
        refused(&render, &png, &fragments);
        let o = drape(&measure);
        let e = text(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "measure {damage:?}: {e}");
        for f in &fragments {
            assert!(e.contains(f), "measure: expected {f:?} in {e}");
        }
    }
    // The same frame undamaged is drawn and measured.
    write_damaged_frame(&frame, ("velocity", 0, 0.0));
    assert!(drape(&render).status.success());
    let o = drape(&measure);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let _ = std::fs::remove_dir_all(&dir);
}

/// `--time -1` is read as a time and refused as one (it was "unexpected
/// argument"); the image size is the renderer's to judge — a width above
/// the command line's old 8192 is drawn — and an image whose buffers
/// would exceed the bound is refused with the estimate, before any
/// allocation: under a 3 GB address-space limit it exits 2, not on an
/// abort.
#[test]
fn render_reads_negative_times_and_refuses_images_beyond_its_memory_bound() {
    let dir = scratch("msg-render");
    let out = run(&dir, 3);
    let png = dir.join("r.png");
    let o = |extra: &[&str]| -> Vec<std::ffi::OsString> {
        let mut a: Vec<std::ffi::OsString> = vec![
            "render".into(),
            out.clone().into(),
            "-o".into(),
            png.clone().into(),
        ];
        a.extend(extra.iter().map(|s| s.into()));
        a
    };
    let args = o(&["--time", "-1"]);
    let args: Vec<&std::ffi::OsStr> = args.iter().map(|s| s.as_os_str()).collect();
    refused(
        &args,
        &png,
        &["--time -1", "not negative", "t = 0 to 0.003 s"],
    );

    let args = o(&["--size", "9000x200"]);
    let args: Vec<&std::ffi::OsStr> = args.iter().map(|s| s.as_os_str()).collect();
    let r = drape(&args);
    assert!(r.status.success(), "{}", text(&r.stderr));
    std::fs::remove_file(&png).unwrap();

    let r = Command::new("prlimit")
        .arg("--as=3000000000")
        .arg(DRAPE)
        .args(o(&["--size", "8192x8192"]))
        .stdin(Stdio::null())
        .output();
    match r {
        Ok(r) => {
            let e = text(&r.stderr);
            assert_eq!(r.status.code(), Some(2), "{e}");
            assert!(
                e.contains("8192x8192") && e.contains("4.7 GiB") && e.contains("2 GiB"),
                "{e}"
            );
            assert!(!png.exists());
        }
        Err(e) => eprintln!("prlimit not available ({e}); the memory-limit case is skipped"),
    }
    let _ = std::fs::remove_dir_all(&dir);
}
