//! Renders, animations and plots of synthetic output directories written
//! here in drape's format (raw-appended VTU, PVD, history CSV).

use std::fs;
use std::path::{Path, PathBuf};

use drape_render::{
    Circle, ExtraPanel, Field, FrameSelect, Layout, RenderError, RenderOptions, RgbImage, View,
    WRINKLE_COLOURS, format_value, gif_info, plot, plot_image_with, render, render_image, viridis,
};

// ---------------------------------------------------------------- writer --

/// One synthetic frame.
struct Synth {
    time: f64,
    step: u64,
    points: Vec<[f64; 3]>,
    /// Displacement per point (default: z of the point, as if the mesh
    /// started flat at z = 0).
    displacement: Vec<[f64; 3]>,
    velocity: Vec<[f64; 3]>,
    cells: Vec<Vec<usize>>,
    vtk_type: u8,
    principal: Vec<[f64; 2]>,
    wrinkle: Vec<i32>,
}

impl Synth {
    fn new(
        time: f64,
        step: u64,
        points: Vec<[f64; 3]>,
        cells: Vec<Vec<usize>>,
        vtk_type: u8,
    ) -> Self {
        let n = points.len();
        let c = cells.len();
        Self {
            time,
            step,
            displacement: points.iter().map(|p| [0.0, 0.0, p[2]]).collect(),
            velocity: vec![[0.0; 3]; n],
            points,
            cells,
            vtk_type,
            principal: (0..c).map(|k| [k as f64, -(k as f64)]).collect(),
            wrinkle: (0..c).map(|k| (k % 3) as i32).collect(),
        }
    }
}

fn block(out: &mut Vec<u8>, bytes: &[u8]) {
    out.extend_from_slice(&(bytes.len() as u64).to_le_bytes());
    out.extend_from_slice(bytes);
}

fn f64s(v: impl IntoIterator<Item = f64>) -> Vec<u8> {
    v.into_iter().flat_map(f64::to_le_bytes).collect()
}

/// The frame as drape's writer would write it.
fn vtu_bytes(s: &Synth) -> Vec<u8> {
    let np = s.points.len();
    let nc = s.cells.len();
    let conn: Vec<u8> = s
        .cells
        .iter()
        .flatten()
        .flat_map(|&i| (i as i64).to_le_bytes())
        .collect();
    let mut off = 0i64;
    let offsets: Vec<u8> = s
        .cells
        .iter()
        .flat_map(|c| {
            off += c.len() as i64;
            off.to_le_bytes()
        })
        .collect();
    let types = vec![s.vtk_type; nc];
    let arrays: Vec<(&str, Vec<u8>)> = vec![
        ("Points", f64s(s.points.iter().flatten().copied())),
        ("connectivity", conn),
        ("offsets", offsets),
        ("types", types),
        (
            "displacement",
            f64s(s.displacement.iter().flatten().copied()),
        ),
        ("velocity", f64s(s.velocity.iter().flatten().copied())),
        ("contact_force", f64s(vec![0.0; 3 * np])),
        ("stress", f64s(vec![1.0; 3 * nc])),
        (
            "principal_stress",
            f64s(s.principal.iter().flatten().copied()),
        ),
        (
            "wrinkle_state",
            s.wrinkle.iter().flat_map(|v| v.to_le_bytes()).collect(),
        ),
    ];
    let mut offs = Vec::new();
    let mut o = 0usize;
    for (_, b) in &arrays {
        offs.push(o);
        o += 8 + b.len();
    }
    let tag = |name: &str, ty: &str, comps: usize, k: usize| {
        let c = if comps == 1 {
            String::new()
        } else {
            format!(" NumberOfComponents=\"{comps}\"")
        };
        format!(
            "        <DataArray type=\"{ty}\" Name=\"{name}\"{c} format=\"appended\" offset=\"{}\"/>\n",
            offs[k]
        )
    };
    let mut x = String::new();
    x.push_str("<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n  <UnstructuredGrid>\n    <FieldData>\n");
    x.push_str(&format!(
        "      <DataArray type=\"Float64\" Name=\"TIME\" NumberOfTuples=\"1\" format=\"ascii\">{}</DataArray>\n    </FieldData>\n",
        s.time
    ));
    x.push_str(&format!(
        "    <Piece NumberOfPoints=\"{np}\" NumberOfCells=\"{nc}\">\n      <PointData>\n"
    ));
    x.push_str(&tag("displacement", "Float64", 3, 4));
    x.push_str(&tag("velocity", "Float64", 3, 5));
    x.push_str(&tag("contact_force", "Float64", 3, 6));
    x.push_str("      </PointData>\n      <CellData>\n");
    x.push_str(&tag("stress", "Float64", 3, 7));
    x.push_str(&tag("principal_stress", "Float64", 2, 8));
    x.push_str(&tag("wrinkle_state", "Int32", 1, 9));
    x.push_str("      </CellData>\n      <Points>\n");
    x.push_str(&tag("Points", "Float64", 3, 0));
    x.push_str("      </Points>\n      <Cells>\n");
    x.push_str(&tag("connectivity", "Int64", 1, 1));
    x.push_str(&tag("offsets", "Int64", 1, 2));
    x.push_str(&tag("types", "UInt8", 1, 3));
    x.push_str("      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n  <AppendedData encoding=\"raw\">\n   _");
    let mut out = x.into_bytes();
    for (_, b) in &arrays {
        block(&mut out, b);
    }
    out.extend_from_slice(b"\n  </AppendedData>\n</VTKFile>\n");
    out
}

/// A fresh directory under the target dir's temp area.
fn test_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("drape-render-test-{}-{name}", std::process::id()));
    let _ = fs::remove_dir_all(&d);
    fs::create_dir_all(d.join("fields")).unwrap();
    d
}

/// Writes the frames, `fields.pvd`, a `summary.json` and a `history.csv`.
fn write_run(dir: &Path, frames: &[Synth]) {
    let mut pvd = String::from(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n  <Collection>\n",
    );
    for f in frames {
        let rel = format!("fields/step_{:06}.vtu", f.step);
        fs::write(dir.join(&rel), vtu_bytes(f)).unwrap();
        pvd.push_str(&format!(
            "    <DataSet timestep=\"{}\" group=\"\" part=\"0\" file=\"{rel}\"/>\n",
            f.time
        ));
    }
    pvd.push_str("  </Collection>\n</VTKFile>\n");
    fs::write(dir.join("fields.pvd"), pvd).unwrap();
    fs::write(
        dir.join("summary.json"),
        r#"{"status": "completed", "title": "Synthetic test run", "steps": 4}"#,
    )
    .unwrap();
    let mut h = String::from(
        "step,time,dt,iterations,kinetic_energy,strain_energy,active_contacts,contact_force,min_gap,a_x,a_y,a_z,external_work,contact_energy,total_energy,min_stretch,cutbacks,taut_fraction,wrinkled_fraction,slack_fraction\n",
    );
    for s in 0..=40 {
        let t = s as f64 * 0.01;
        h.push_str(&format!(
            "{s},{t},0.01,{},{},{},0,{},{},0,0,{},{},0,0,1,{},0.5,0.3,0.2\n",
            if s == 0 { 0 } else { 2 + s % 3 },
            0.5 * t * t,
            0.1 * t,
            if t > 0.2 { 1.0 } else { 0.0 },
            0.2 - t,
            -t * t,
            t,
            if s == 17 { 1 } else { 0 },
        ));
    }
    fs::write(dir.join("history.csv"), h).unwrap();
}

/// A flat square sheet of `n` x `n` squares (two triangles each) centred at
/// `(cx, cy)`, side `a`, at height `z`, with its nodes numbered from `base`.
fn sheet(
    cx: f64,
    cy: f64,
    a: f64,
    z: f64,
    n: usize,
    base: usize,
) -> (Vec<[f64; 3]>, Vec<Vec<usize>>) {
    let mut p = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            p.push([
                cx - a / 2.0 + a * i as f64 / n as f64,
                cy - a / 2.0 + a * j as f64 / n as f64,
                z,
            ]);
        }
    }
    let id = |i: usize, j: usize| base + j * (n + 1) + i;
    let mut c = Vec::new();
    for j in 0..n {
        for i in 0..n {
            c.push(vec![id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            c.push(vec![id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    (p, c)
}

/// Two sheets: A (x < 0) at z = 0 and B (x > 0) at z = -0.1.
fn two_heights(step: u64, time: f64) -> Synth {
    let (mut p, mut c) = sheet(-0.6, 0.0, 0.8, 0.0, 4, 0);
    let (p2, c2) = sheet(0.6, 0.0, 0.8, -0.1, 4, p.len());
    p.extend(p2);
    c.extend(c2);
    Synth::new(time, step, p, c, 5)
}

fn top_opts(dir: &Path, name: &str) -> RenderOptions {
    RenderOptions {
        view: View::Top,
        edges: Some(false),
        output: Some(dir.join(name)),
        ..RenderOptions::default()
    }
}

fn pixel_at(img: &RgbImage, xy: (f64, f64)) -> [u8; 3] {
    img.get(xy.0 as u32, xy.1 as u32).expect("inside the image")
}

// ----------------------------------------------------------------- tests --

#[test]
fn image_has_the_requested_size() {
    let dir = test_dir("size");
    write_run(&dir, &[two_heights(0, 0.0), two_heights(10, 0.1)]);
    for (w, h) in [(640, 480), (1200, 900), (333, 777)] {
        for layout in [Layout::Single, Layout::Grid { panels: 6 }] {
            let opts = RenderOptions {
                width: w,
                height: h,
                layout,
                output: Some(dir.join("out.png")),
                ..RenderOptions::default()
            };
            let r = render(&dir, &opts).unwrap();
            assert_eq!((r.width, r.height), (w, h));
            let img = RgbImage::read_png(&dir.join("out.png")).unwrap();
            assert_eq!((img.width, img.height), (w, h), "{layout:?}");
        }
    }
    // The smallest figure, with many panels (fewer frames than panels).
    let opts = RenderOptions {
        width: 160,
        height: 120,
        layout: Layout::Grid { panels: 24 },
        output: Some(dir.join("tiny.png")),
        ..RenderOptions::default()
    };
    render(&dir, &opts).unwrap();
    let img = RgbImage::read_png(&dir.join("tiny.png")).unwrap();
    assert_eq!((img.width, img.height), (160, 120));
    // The default output goes into the directory.
    let r = render(&dir, &RenderOptions::default()).unwrap();
    assert_eq!(r.output.as_deref(), Some(dir.join("render.png").as_path()));
    let img = RgbImage::read_png(&dir.join("render.png")).unwrap();
    assert_eq!((img.width, img.height), (1200, 900));
    fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn flat_fabric_at_two_heights_shows_the_colour_map_ends() {
    let dir = test_dir("two-heights");
    write_run(&dir, &[two_heights(0, 0.0)]);
    for shading in [true, false] {
        let opts = RenderOptions {
            shading,
            ..top_opts(&dir, "two.png")
        };
        let r = render(&dir, &opts).unwrap();
        assert_eq!(r.range, (-0.1, 0.0));
        let img = RgbImage::read_png(&dir.join("two.png")).unwrap();
        let proj = r
            .projection
            .expect("single renders report their projection");
        // Sheet A (z = 0, the maximum) is yellow, sheet B (the minimum) dark
        // blue, at their centres and near their corners.
        for (x, y) in [(-0.6, 0.0), (-0.9, 0.3), (-0.3, -0.35)] {
            assert_eq!(
                pixel_at(&img, proj.pixel([x, y, 0.0])),
                viridis(1.0),
                "A at {x},{y}"
            );
        }
        for (x, y) in [(0.6, 0.0), (0.9, -0.3), (0.3, 0.35)] {
            assert_eq!(
                pixel_at(&img, proj.pixel([x, y, -0.1])),
                viridis(0.0),
                "B at {x},{y}"
            );
        }
        assert_eq!(viridis(0.0), [0x44, 0x01, 0x54]);
        assert_eq!(viridis(1.0), [0xfd, 0xe7, 0x25]);
        // Between the sheets: white background.
        assert_eq!(pixel_at(&img, proj.pixel([0.0, 0.0, 0.0])), [255, 255, 255]);
        // Top view: x to the right, y up; A is left of B.
        let (ax, ay) = proj.pixel([-0.6, 0.3, 0.0]);
        let (bx, by) = proj.pixel([0.6, 0.0, 0.0]);
        assert!(ax < bx && ay < by);
        assert!(ax > 0.0 && bx < 1200.0 * 0.85);
    }
    fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn the_nearer_surface_hides_the_farther_one_whatever_the_order() {
    // Sheet B (low) is written after sheet A (high) and overlaps it: seen
    // from the top A must win; seen from below... (side view: B is in front
    // only where it is nearer to the camera).
    let dir = test_dir("zbuffer");
    let (mut p, mut c) = sheet(0.0, 0.0, 1.0, 0.0, 3, 0);
    let (p2, c2) = sheet(0.2, 0.0, 1.0, -0.1, 3, p.len());
    p.extend(p2);
    c.extend(c2);
    write_run(&dir, &[Synth::new(0.0, 0, p, c, 5)]);
    let (img, r) = render_image(&dir, &top_opts(&dir, "z.png")).unwrap();
    let proj = r.projection.unwrap();
    // Overlap region: A's colour (the maximum).
    assert_eq!(pixel_at(&img, proj.pixel([0.1, 0.0, 0.0])), viridis(1.0));
    // Only B: its colour.
    assert_eq!(pixel_at(&img, proj.pixel([0.65, 0.0, -0.1])), viridis(0.0));
    fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn colour_bar_end_labels_are_the_field_min_and_max() {
    let dir = test_dir("labels");
    let mut f = two_heights(0, 0.0);
    let mut g = two_heights(10, 0.25);
    // Speeds 1.5 .. 5 (3-4-0 triangle) in the second frame.
    for (k, v) in g.velocity.iter_mut().enumerate() {
        *v = if k == 0 {
            [3.0, 4.0, 0.0]
        } else {
            [0.0, 0.0, -1.5]
        };
    }
    f.velocity.iter_mut().for_each(|v| *v = [0.0, 0.0, -2.0]);
    // Displacement range -0.1234567 .. 0.0421 in the second frame.
    g.displacement[3] = [0.0, 0.0, 0.0421];
    g.displacement[30] = [0.0, 0.0, -0.1234567];
    write_run(&dir, &[f, g]);
    let cases: [(Field, FrameSelect, f64, f64); 4] = [
        (Field::DisplacementZ, FrameSelect::Last, -0.1234567, 0.0421),
        (Field::Velocity, FrameSelect::Last, 1.5, 5.0),
        (Field::Velocity, FrameSelect::Step(0), 2.0, 2.0),
        (Field::PrincipalStressMax, FrameSelect::Time(0.0), 0.0, 63.0),
    ];
    for (field, frame, lo, hi) in cases {
        let opts = RenderOptions {
            field,
            frame,
            ..top_opts(&dir, "l.png")
        };
        let r = render(&dir, &opts).unwrap();
        assert_eq!(r.range, (lo, hi), "{field}");
        let first = r.colorbar_labels.first().unwrap();
        let last = r.colorbar_labels.last().unwrap();
        assert_eq!(first, &format_value(lo), "{field}");
        assert_eq!(last, &format_value(hi), "{field}");
        let parsed: f64 = first.parse().unwrap();
        assert!(
            (parsed - lo).abs() <= 1e-3 * lo.abs().max(1e-12),
            "{first} vs {lo}"
        );
        let parsed: f64 = last.parse().unwrap();
        assert!(
            (parsed - hi).abs() <= 1e-3 * hi.abs().max(1e-12),
            "{last} vs {hi}"
        );
        assert!(r.caption.starts_with(field.name()));
        assert!(r.caption.contains(&format!("({})", field.unit())));
    }
    assert_eq!(format_value(-0.1234567), "-0.1235");
    // The grid shares one scale over its frames.
    let opts = RenderOptions {
        layout: Layout::Grid { panels: 6 },
        ..top_opts(&dir, "g.png")
    };
    let r = render(&dir, &opts).unwrap();
    assert_eq!(r.frames.len(), 2);
    assert_eq!(r.range, (-0.1234567, 0.0421));
    // Wrinkle state: a legend of the three states.
    let opts = RenderOptions {
        field: Field::WrinkleState,
        ..top_opts(&dir, "w.png")
    };
    let r = render(&dir, &opts).unwrap();
    assert_eq!(r.colorbar_labels, ["taut", "wrinkled", "slack"]);
    assert_eq!(r.caption, "wrinkle_state");
    fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn colour_bar_shows_the_map_from_min_at_the_bottom_to_max_at_the_top() {
    let dir = test_dir("bar");
    write_run(&dir, &[two_heights(0, 0.0)]);
    let (img, _) = render_image(&dir, &top_opts(&dir, "b.png")).unwrap();
    // Scan the right fifth of the image for the bar's column: the topmost
    // and bottommost viridis-end pixels.
    let (mut top_hi, mut bottom_lo) = (None, None);
    for y in 0..img.height {
        for x in img.width * 4 / 5..img.width {
            let c = img.get(x, y).unwrap();
            if c == viridis(1.0) && top_hi.is_none() {
                top_hi = Some(y);
            }
            if c == viridis(0.0) {
                bottom_lo = Some(y);
            }
        }
    }
    let (t, b) = (
        top_hi.expect("max colour in the bar"),
        bottom_lo.expect("min colour"),
    );
    assert!(t < b, "max at the top ({t}), min at the bottom ({b})");
    assert!(b - t > img.height / 3, "a tall bar");
    fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn animation_has_one_frame_per_written_step() {
    let dir = test_dir("anim");
    let frames: Vec<Synth> = (0..5)
        .map(|k| {
            let mut s = two_heights(k * 10, k as f64 * 0.05);
            for p in &mut s.points {
                p[2] -= 0.01 * k as f64;
            }
            s
        })
        .collect();
    write_run(&dir, &frames);
    let opts = RenderOptions {
        layout: Layout::Animation { frame_delay_ms: 80 },
        width: 320,
        height: 240,
        output: Some(dir.join("a.gif")),
        ..RenderOptions::default()
    };
    let r = render(&dir, &opts).unwrap();
    assert_eq!(r.frames.len(), 5);
    assert_eq!(
        r.frames.iter().map(|f| f.step).collect::<Vec<_>>(),
        [0, 10, 20, 30, 40]
    );
    let (n, w, h) = gif_info(&dir.join("a.gif")).unwrap();
    assert_eq!((n, w, h), (5, 320, 240));
    // The default name; a PNG name for an animation is refused.
    let opts = RenderOptions {
        output: None,
        ..opts
    };
    let r = render(&dir, &opts).unwrap();
    assert_eq!(r.output.unwrap(), dir.join("animation.gif"));
    let bad = RenderOptions {
        output: Some(dir.join("a.png")),
        ..opts
    };
    assert!(matches!(
        render(&dir, &bad),
        Err(RenderError::InvalidOption(_))
    ));
    fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn grid_picks_frames_spread_over_the_run() {
    let dir = test_dir("grid");
    let frames: Vec<Synth> = (0..20)
        .map(|k| two_heights(k * 5, k as f64 * 0.01))
        .collect();
    write_run(&dir, &frames);
    let opts = RenderOptions {
        layout: Layout::Grid { panels: 6 },
        output: Some(dir.join("g.png")),
        ..RenderOptions::default()
    };
    let r = render(&dir, &opts).unwrap();
    let steps: Vec<u64> = r.frames.iter().map(|f| f.step).collect();
    assert_eq!(steps.len(), 6);
    assert_eq!(steps[0], 0);
    assert_eq!(*steps.last().unwrap(), 95);
    assert!(steps.windows(2).all(|w| w[0] < w[1]));
    fs::remove_dir_all(&dir).unwrap();
}

/// A flat T6 or T10 mesh of two elements, at height z.
fn high_order(npe: usize, z: f64) -> (Vec<[f64; 3]>, Vec<Vec<usize>>, u8) {
    // Reference coordinates of the nodes (Gmsh/VTK order).
    let r6 = [
        (0., 0.),
        (1., 0.),
        (0., 1.),
        (0.5, 0.),
        (0.5, 0.5),
        (0., 0.5),
    ];
    let t = 1.0 / 3.0;
    let r10 = [
        (0., 0.),
        (1., 0.),
        (0., 1.),
        (t, 0.),
        (2. * t, 0.),
        (2. * t, t),
        (t, 2. * t),
        (0., 2. * t),
        (0., t),
        (t, t),
    ];
    let refs: &[(f64, f64)] = if npe == 6 { &r6 } else { &r10 };
    let mut p = Vec::new();
    let mut cells = Vec::new();
    // Element 1: (0,0) (1,0) (0,1); element 2: (1,1) (0,1) (1,0) — nodes
    // duplicated along the shared edge (fine for rendering).
    for (o, sx, sy) in [((0.0, 0.0), 1.0, 1.0), ((1.0, 1.0), -1.0, -1.0)] {
        let base = p.len();
        for &(u, v) in refs {
            p.push([o.0 + sx * u, o.1 + sy * v, z]);
        }
        cells.push((base..base + npe).collect());
    }
    (p, cells, if npe == 6 { 22 } else { 69 })
}

#[test]
fn quadratic_and_cubic_triangles_are_drawn_whole() {
    for npe in [6, 10] {
        let dir = test_dir(&format!("t{npe}"));
        let (p, c, ty) = high_order(npe, 0.0);
        let mut s = Synth::new(0.0, 0, p, c, ty);
        // Displacement z = x: the colour varies across each element.
        s.displacement = s.points.iter().map(|q| [0.0, 0.0, q[0]]).collect();
        write_run(&dir, &[s]);
        let (img, r) = render_image(&dir, &top_opts(&dir, "h.png")).unwrap();
        assert_eq!(r.range, (0.0, 1.0));
        let proj = r.projection.unwrap();
        // Every point of both elements is painted (sub-triangles cover the
        // element), with the colour of its x (linear in x here).
        for (x, y) in [
            (0.1, 0.1),
            (0.45, 0.45),
            (0.9, 0.05),
            (0.55, 0.55),
            (0.95, 0.9),
            (0.5, 0.1),
        ] {
            let c = pixel_at(&img, proj.pixel([x, y, 0.0]));
            let want = viridis(x);
            let diff = c
                .iter()
                .zip(&want)
                .map(|(a, b)| (*a as i32 - *b as i32).abs())
                .max()
                .unwrap();
            assert!(diff <= 6, "T{npe} at ({x},{y}): {c:?} vs {want:?}");
        }
        // Cell fields: constant per element.
        let opts = RenderOptions {
            field: Field::WrinkleState,
            ..top_opts(&dir, "w.png")
        };
        let (img, r) = render_image(&dir, &opts).unwrap();
        let proj = r.projection.unwrap();
        assert_eq!(
            pixel_at(&img, proj.pixel([0.2, 0.2, 0.0])),
            WRINKLE_COLOURS[0]
        );
        assert_eq!(
            pixel_at(&img, proj.pixel([0.8, 0.8, 0.0])),
            WRINKLE_COLOURS[1]
        );
        fs::remove_dir_all(&dir).unwrap();
    }
}

/// A box under sheet A of [`two_heights`] reaching out to x = 0.1 (between
/// the sheets), and a mesh obstacle, which is not drawn.
const BOX_AND_MESH: &str = r#"
title = "x"
[[obstacle]]
shape = "box"
min = [-1.0, -0.2, -0.5]
max = [0.1, 0.2, -0.05]
[[obstacle]]
shape = "mesh"
path = "thing.obj"
"#;

#[test]
fn obstacles_from_the_scenario_are_drawn_grey_behind_the_fabric() {
    let dir = test_dir("obstacles");
    write_run(&dir, &[two_heights(0, 0.0)]);
    fs::write(dir.join("scenario.toml"), BOX_AND_MESH).unwrap();
    let (img, r) = render_image(&dir, &top_opts(&dir, "o.png")).unwrap();
    assert_eq!(r.obstacles, 1);
    assert_eq!(r.notices.len(), 1, "{:?}", r.notices);
    let proj = r.projection.clone().unwrap();
    // The box top between the sheets: grey.
    let c = pixel_at(&img, proj.pixel([0.0, 0.0, -0.05]));
    assert!(
        c[0] == c[1] && c[1] == c[2] && (120..230).contains(&c[0]),
        "{c:?}"
    );
    // Over the box, the fabric (nearer) shows.
    assert_eq!(pixel_at(&img, proj.pixel([-0.6, 0.0, 0.0])), viridis(1.0));
    // Without obstacles: white there.
    let opts = RenderOptions {
        obstacles: false,
        ..top_opts(&dir, "o.png")
    };
    let (img, r) = render_image(&dir, &opts).unwrap();
    assert_eq!(r.obstacles, 0);
    assert_eq!(
        pixel_at(&img, proj.pixel([0.0, 0.0, -0.05])),
        [255, 255, 255]
    );
    // Perspective and side views of the same scene render too.
    for view in [View::Side, View::Perspective] {
        let opts = RenderOptions {
            view,
            ..top_opts(&dir, "o.png")
        };
        render(&dir, &opts).unwrap();
    }
    fs::remove_dir_all(&dir).unwrap();
}

/// Issue 35: a fabric lying on an obstacle's face — on it exactly, or a
/// tenth of a millimetre into it, as penalty contact leaves it — is drawn
/// over the face, from above and in perspective: no grey obstacle pixel
/// inside the fabric's silhouette (the face showed through in slivers
/// where the two were coplanar). The fabric is drawn first and the
/// obstacles pushed back by a depth bias of 3e-3 of the scene's diagonal
/// (about 2.4 mm here), so that a tie or a shallow penetration goes to
/// the fabric. Sampled every 2 mm on the sheet, 1 cm in from its edge
/// (the edge's pixels blend both, by the anti-aliasing).
#[test]
fn a_fabric_lying_on_a_face_hides_it() {
    let dir = test_dir("coplanar");
    fs::write(
        dir.join("scenario.toml"),
        "[[obstacle]]\nshape = \"box\"\nmin = [-0.3, -0.3, -0.2]\nmax = [0.3, 0.3, 0.0]\n",
    )
    .unwrap();
    for depth in [0.0, 1e-4] {
        let (p, c) = sheet(0.0, 0.0, 0.4, -depth, 16, 0);
        write_run(&dir, &[Synth::new(0.0, 0, p, c, 5)]);
        for view in [View::Top, View::Perspective] {
            let opts = RenderOptions {
                view,
                ..top_opts(&dir, "coplanar.png")
            };
            let (img, r) = render_image(&dir, &opts).unwrap();
            assert_eq!(r.obstacles, 1);
            let proj = r.projection.clone().unwrap();
            // The box's face around the sheet is drawn (grey).
            let c = pixel_at(&img, proj.pixel([0.25, 0.25, 0.0]));
            assert!(
                c[0] == c[1] && c[1] == c[2] && c[0] < 255,
                "{view:?}: {c:?}"
            );
            let mut grey = Vec::new();
            for i in 0..=190 {
                for j in 0..=190 {
                    let at = [-0.19 + 0.002 * i as f64, -0.19 + 0.002 * j as f64, -depth];
                    let c = pixel_at(&img, proj.pixel(at));
                    if c[0] == c[1] && c[1] == c[2] {
                        grey.push((at, c));
                    }
                }
            }
            assert!(
                grey.is_empty(),
                "{view:?}, {depth} m into the face: {} grey pixels inside the fabric, e.g. {:?}",
                grey.len(),
                &grey[..grey.len().min(5)]
            );
        }
    }
    fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn plot_writes_a_png_of_the_requested_size() {
    let dir = test_dir("plot");
    write_run(&dir, &[two_heights(0, 0.0)]);
    for (w, h) in [(1200, 900), (800, 600)] {
        let out = dir.join("p.png");
        let r = plot(&dir, &out, w, h).unwrap();
        assert_eq!(r.rows, 41);
        assert_eq!(r.monitors, ["a"]);
        assert_eq!(r.panels.len(), 6);
        let img = RgbImage::read_png(&out).unwrap();
        assert_eq!((img.width, img.height), (w, h));
        // Not blank: lines and text.
        let dark = img
            .data
            .chunks(3)
            .filter(|p| p.iter().all(|&v| v < 100))
            .count();
        assert!(dark > 1000, "{dark} dark pixels");
    }
    assert!(matches!(
        plot(&dir, &dir.join("p.gif"), 800, 600),
        Err(RenderError::InvalidOption(_))
    ));
    fs::remove_dir_all(&dir).unwrap();
}

/// Issue 35: the state panel says what it shows. Without a tension-field
/// model (`wrinkling = "none"`, the default) nothing wrinkles: the states
/// classify the principal stresses, and the panel is titled so; with one,
/// or when the scenario cannot say, it is the wrinkling state.
#[test]
fn the_state_panel_is_labelled_for_the_material() {
    let dir = test_dir("states");
    write_run(&dir, &[two_heights(0, 0.0)]);
    let title = |scenario: Option<&str>| {
        match scenario {
            Some(text) => fs::write(dir.join("scenario.toml"), text).unwrap(),
            None => {
                let _ = fs::remove_file(dir.join("scenario.toml"));
            }
        }
        let (_, r) = plot_image_with(&dir, 800, 600, &[]).unwrap();
        assert_eq!(r.panels.len(), 6);
        r.panels[4].clone()
    };
    let stresses = "Stress state, no tension-field model (fraction of elements)";
    let wrinkles = "Wrinkling state (fraction of elements)";
    assert_eq!(title(Some("[material]\nwrinkling = \"none\"\n")), stresses);
    assert_eq!(title(Some("[material]\nthickness = 1e-3\n")), stresses);
    assert_eq!(
        title(Some("[material]\nwrinkling = \"relaxed-energy\"\n")),
        wrinkles
    );
    assert_eq!(
        title(Some("[material]\nwrinkling = \"stress-projection\"\n")),
        wrinkles
    );
    assert_eq!(title(None), wrinkles);
    fs::remove_dir_all(&dir).unwrap();
}

/// Circles (a drape tester's pedestal and specimen) are stroked over the
/// fabric where the projection puts them, the camera fits them in, and a
/// circle that cannot be is refused.
#[test]
fn circles_are_drawn_over_the_fabric() {
    let dir = test_dir("circles");
    write_run(&dir, &[two_heights(0, 0.0)]);
    let red = [230, 20, 20];
    // One over sheet A, one larger than the whole scene.
    let circles = vec![
        Circle {
            center: [-0.6, 0.0, 0.0],
            normal: [0.0, 0.0, 1.0],
            radius: 0.2,
            color: red,
            dashed: false,
        },
        Circle {
            center: [0.0, 0.0, 0.0],
            normal: [0.0, 0.0, 1.0],
            radius: 2.0,
            color: red,
            dashed: true,
        },
    ];
    let opts = RenderOptions {
        circles,
        caption: Some("a caption".into()),
        ..top_opts(&dir, "circles.png")
    };
    let (img, r) = render_image(&dir, &opts).unwrap();
    let proj = r.projection.unwrap();
    for t in [0.0f64, 1.0, 2.5, 4.0] {
        let on = [-0.6 + 0.2 * t.cos(), 0.2 * t.sin(), 0.0];
        assert_eq!(pixel_at(&img, proj.pixel(on)), red, "at angle {t}");
    }
    // Inside it the fabric; the large circle is inside the picture.
    assert_eq!(pixel_at(&img, proj.pixel([-0.6, 0.0, 0.0])), viridis(1.0));
    for p in [
        [2.0, 0.0, 0.0],
        [-2.0, 0.0, 0.0],
        [0.0, 2.0, 0.0],
        [0.0, -2.0, 0.0],
    ] {
        let (x, y) = proj.pixel(p);
        assert!(
            x > 0.0 && x < 1200.0 && y > 0.0 && y < 900.0,
            "{p:?} at {x}, {y}"
        );
    }
    let bad = RenderOptions {
        circles: vec![Circle {
            center: [0.0; 3],
            normal: [0.0; 3],
            radius: 0.1,
            color: red,
            dashed: false,
        }],
        ..top_opts(&dir, "bad.png")
    };
    assert!(
        matches!(render(&dir, &bad), Err(RenderError::InvalidOption(m)) if m.contains("circle 0"))
    );
    fs::remove_dir_all(&dir).unwrap();
}

/// Panels computed by the caller (a drape tester's coefficient, frame by
/// frame) come after the history's, two a row.
#[test]
fn extra_plot_panels_follow_the_history() {
    let dir = test_dir("extra-panels");
    write_run(&dir, &[two_heights(0, 0.0)]);
    let extra = vec![
        ExtraPanel {
            title: "Drape coefficient".into(),
            y_label: "DC".into(),
            time: vec![0.0, 0.1, 0.2],
            series: vec![("DC".into(), vec![1.0, 0.6, 0.5])],
            integer: false,
        },
        ExtraPanel {
            title: "Folds".into(),
            y_label: "folds".into(),
            time: vec![0.0, 0.1, 0.2],
            series: vec![("folds".into(), vec![0.0, 6.0, 6.0])],
            integer: true,
        },
    ];
    let (img, r) = plot_image_with(&dir, 1000, 1000, &extra).unwrap();
    assert_eq!(r.panels.len(), 8);
    assert_eq!(r.panels[6..], ["Drape coefficient", "Folds"]);
    assert_eq!((img.width, img.height), (1000, 1000));
    // The last row is drawn: dark pixels (axes, lines, text) in its band.
    let dark = (800..1000)
        .flat_map(|y| (0..1000).map(move |x| (x, y)))
        .filter(|&(x, y)| img.get(x, y).is_some_and(|p| p.iter().all(|&v| v < 100)))
        .count();
    assert!(dark > 500, "{dark} dark pixels in the last row");
    fs::remove_dir_all(&dir).unwrap();
}

/// Long, and kept whole: a catalogue of bad inputs, each a few lines
/// that break one thing and check the error names the file.
#[test]
fn bad_inputs_give_errors_naming_the_file() {
    let dir = test_dir("bad");
    let opts = top_opts(&dir, "x.png");
    // Missing directory.
    let missing = dir.join("nope");
    let e = render(&missing, &opts).unwrap_err();
    assert!(e.to_string().contains("nope"), "{e}");
    assert!(plot(&missing, &dir.join("p.png"), 800, 600).is_err());
    // No fields.pvd.
    let e = render(&dir, &opts).unwrap_err();
    assert!(e.to_string().contains("fields.pvd"), "{e}");
    // A good run, then damage it.
    write_run(&dir, &[two_heights(0, 0.0), two_heights(10, 0.1)]);
    let vtu = dir.join("fields/step_000010.vtu");
    let bytes = fs::read(&vtu).unwrap();
    for cut in [bytes.len() - 40, bytes.len() / 2, 900, 100, 0] {
        fs::write(&vtu, &bytes[..cut]).unwrap();
        let e = render(&dir, &opts).unwrap_err();
        assert!(e.to_string().contains("step_000010.vtu"), "cut {cut}: {e}");
    }
    // Garbage in the appended block: wrong byte counts.
    let mut g = bytes.clone();
    let us = g.iter().position(|&b| b == b'_').unwrap();
    g[us + 1..us + 9].copy_from_slice(&u64::MAX.to_le_bytes());
    fs::write(&vtu, &g).unwrap();
    assert!(render(&dir, &opts).is_err());
    fs::write(&vtu, &bytes).unwrap();
    render(&dir, &opts).unwrap();
    // Unknown step, bad field name, bad sizes, bad extension.
    let e = render(
        &dir,
        &RenderOptions {
            frame: FrameSelect::Step(7),
            ..opts.clone()
        },
    )
    .unwrap_err();
    assert!(
        matches!(e, RenderError::StepNotFound { step: 7, .. }),
        "{e}"
    );
    assert!(e.to_string().contains("0, 10"), "{e}");
    assert!("speed".parse::<Field>().is_err());
    assert!("oblique".parse::<View>().is_err());
    assert!(
        render(
            &dir,
            &RenderOptions {
                width: 10,
                ..opts.clone()
            }
        )
        .is_err()
    );
    assert!(
        render(
            &dir,
            &RenderOptions {
                supersample: 9,
                ..opts.clone()
            }
        )
        .is_err()
    );
    assert!(
        render(
            &dir,
            &RenderOptions {
                range: Some((1.0, 0.0)),
                ..opts.clone()
            }
        )
        .is_err()
    );
    assert!(
        render(
            &dir,
            &RenderOptions {
                output: Some(dir.join("x.jpg")),
                ..opts.clone()
            }
        )
        .is_err()
    );
    assert!(
        render(
            &dir,
            &RenderOptions {
                layout: Layout::Grid { panels: 0 },
                ..opts.clone()
            }
        )
        .is_err()
    );
    // A bad scenario.
    let sc = dir.join("bad.toml");
    fs::write(
        &sc,
        "[[obstacle]]\nshape = \"sphere\"\ncenter = [0, 0, 0]\n",
    )
    .unwrap();
    let e = render(
        &dir,
        &RenderOptions {
            scenario: Some(sc.clone()),
            ..opts.clone()
        },
    )
    .unwrap_err();
    assert!(
        e.to_string().contains("bad.toml") && e.to_string().contains("radius"),
        "{e}"
    );
    fs::write(&sc, "this is [ not toml").unwrap();
    assert!(
        render(
            &dir,
            &RenderOptions {
                scenario: Some(sc),
                ..opts.clone()
            }
        )
        .is_err()
    );
    // A frame without the field's array.
    let mut nb = bytes.clone();
    let pat = b"Name=\"velocity\"";
    let at = nb.windows(pat.len()).position(|w| w == pat).unwrap();
    nb[at + pat.len() - 2] = b'z'; // "velocitz"
    fs::write(&vtu, &nb).unwrap();
    let e = render(
        &dir,
        &RenderOptions {
            field: Field::Velocity,
            ..opts.clone()
        },
    )
    .unwrap_err();
    assert!(matches!(e, RenderError::MissingArray { .. }), "{e}");
    fs::write(&vtu, &bytes).unwrap();
    // A bad pvd and a bad history.
    fs::write(
        dir.join("fields.pvd"),
        "<VTKFile type=\"Collection\"><Collection><DataSet timestep=\"x\" file=\"a.vtu\"/>",
    )
    .unwrap();
    let e = render(&dir, &opts).unwrap_err();
    assert!(e.to_string().contains("fields.pvd"), "{e}");
    fs::write(
        dir.join("fields.pvd"),
        "<VTKFile type=\"Collection\"><Collection></Collection></VTKFile>",
    )
    .unwrap();
    assert!(matches!(
        render(&dir, &opts),
        Err(RenderError::NoFrames { .. })
    ));
    fs::write(dir.join("history.csv"), "step,time\n0,0\n1,abc\n2,0.2\n").unwrap();
    let e = plot(&dir, &dir.join("p.png"), 800, 600).unwrap_err();
    assert!(
        e.to_string().contains("history.csv") && e.to_string().contains("line 3"),
        "{e}"
    );
    fs::write(dir.join("history.csv"), "").unwrap();
    assert!(plot(&dir, &dir.join("p.png"), 800, 600).is_err());
    fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn every_field_renders() {
    let dir = test_dir("fields");
    write_run(&dir, &[two_heights(0, 0.0)]);
    for field in Field::ALL {
        for view in [View::Top, View::Side, View::Perspective] {
            let opts = RenderOptions {
                field,
                view,
                width: 400,
                height: 300,
                supersample: 2,
                output: Some(dir.join("f.png")),
                ..RenderOptions::default()
            };
            let r = render(&dir, &opts).unwrap();
            assert_eq!(r.field, field);
        }
    }
    fs::remove_dir_all(&dir).unwrap();
}

/// Issue 46: obstacles are numbered from 0, `obstacle[i]`, as `drape check`
/// and `drape measure` number them (the renderer said "obstacle 2" for
/// `obstacle[1]`).
#[test]
fn obstacles_are_named_as_check_and_measure_name_them() {
    let text = BOX_AND_MESH;
    let (shapes, notices) = drape_render::parse_obstacles(Path::new("s.toml"), text).unwrap();
    assert_eq!(shapes.len(), 1);
    assert_eq!(notices.len(), 1);
    assert!(
        notices[0].starts_with("obstacle[1] (mesh thing.obj)"),
        "{notices:?}"
    );
    let bad = format!(
        "{text}[[obstacle]]\nshape = \"sphere\"\ncenter = [0.0, 0.0, 0.0]\nradius = -1.0\n"
    );
    let e = drape_render::parse_obstacles(Path::new("s.toml"), &bad).unwrap_err();
    assert!(
        e.to_string().contains("obstacle[2]: radius must be > 0"),
        "{e}"
    );
}
