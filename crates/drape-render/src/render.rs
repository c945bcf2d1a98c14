//! Figures of the fabric: one frame, a grid of frames, an animation.

use std::path::{Path, PathBuf};
use std::rc::Rc;

use crate::colorbar::Colorbar;
use crate::colormap::ColorMap;
use crate::error::{RenderError, Result};
use crate::field::{Field, FieldValues, WRINKLE_STATES};
use crate::geom::{Aabb, V3, add, cross, normalize, obstacle_triangles, sub};
use crate::image::RgbImage;
use crate::outdir::{FrameEntry, FrameSelect, OutputDir};
use crate::overlay::{Circle, stroke};
use crate::raster::{Buffer, Camera, Paint, RasterTri, Style, View};
use crate::scenario::{Obstacle, read_obstacles};
use crate::text::{self, Align, Weight};
use crate::vtu::{VTK_LAGRANGE_TRIANGLE, VTK_QUADRATIC_TRIANGLE, read_vtu};

/// What kind of figure to make.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Layout {
    /// One frame (chosen by [`RenderOptions::frame`]), PNG.
    #[default]
    Single,
    /// About `panels` frames spread over the run, one figure with a shared
    /// colour scale, PNG.
    Grid {
        /// Number of panels (1–24; fewer if fewer frames were written).
        panels: usize,
    },
    /// Every frame of `fields.pvd`, one GIF frame each, shared colour scale
    /// and camera.
    Animation {
        /// Delay between frames, ms (rounded to GIF's 10 ms); the last frame
        /// is held 1.5 s longer.
        frame_delay_ms: u32,
    },
}

/// How to render.
#[derive(Debug, Clone, PartialEq)]
pub struct RenderOptions {
    /// Single frame, grid or animation.
    pub layout: Layout,
    /// The frame of a single render (ignored by grids and animations).
    pub frame: FrameSelect,
    /// Direction of view.
    pub view: View,
    /// Field the fabric is coloured by.
    pub field: Field,
    /// Image width, pixels (160–10000).
    pub width: u32,
    /// Image height, pixels (120–10000).
    pub height: u32,
    /// Output file; `None`: [`default_output`] in the output directory.
    pub output: Option<PathBuf>,
    /// Scenario file whose `[[obstacle]]` tables are drawn; `None`:
    /// `DIR/scenario.toml` if it exists.
    pub scenario: Option<PathBuf>,
    /// Draw the obstacles (grey).
    pub obstacles: bool,
    /// Colour scale `(min, max)`; `None`: the field's range over the frames
    /// shown.
    pub range: Option<(f64, f64)>,
    /// Outline the elements: `Some(true)` always, `Some(false)` never,
    /// `None` when they are at least 6 pixels across.
    pub edges: Option<bool>,
    /// Light shading (a light at the camera; a surface facing the camera
    /// shows its exact colour-map colour).
    pub shading: bool,
    /// Supersampling factor per axis for anti-aliasing (1–4).
    pub supersample: u32,
    /// Circles stroked over single frames and animations, on top of
    /// everything (a drape tester's pedestal and specimen); the camera
    /// fits them in.
    pub circles: Vec<Circle>,
    /// Text added to the subtitle of a single frame (a measurement).
    pub caption: Option<String>,
}

impl Default for RenderOptions {
    fn default() -> Self {
        Self {
            layout: Layout::Single,
            frame: FrameSelect::Last,
            view: View::Perspective,
            field: Field::DisplacementZ,
            width: 1200,
            height: 900,
            output: None,
            scenario: None,
            obstacles: true,
            range: None,
            edges: None,
            shading: true,
            supersample: 3,
            circles: Vec::new(),
            caption: None,
        }
    }
}

/// What a render drew.
#[derive(Debug, Clone, PartialEq)]
pub struct RenderReport {
    /// The file written (`None` from [`render_image`]).
    pub output: Option<PathBuf>,
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// The frames drawn, in order (one per panel or animation frame).
    pub frames: Vec<FrameEntry>,
    /// The field.
    pub field: Field,
    /// The colour scale: `(min, max)` of the field over the frames drawn
    /// (or the range asked for); `(0, 2)` for the wrinkle state.
    pub range: (f64, f64),
    /// The colour bar's labels from bottom (min) to top (max); for the
    /// wrinkle state the legend's names.
    pub colorbar_labels: Vec<String>,
    /// The colour bar's caption: field name and unit.
    pub caption: String,
    /// Number of obstacles drawn.
    pub obstacles: usize,
    /// Things the user should know (e.g. a mesh obstacle not drawn).
    pub notices: Vec<String>,
    /// Where points of the scene land in the image (single frames and
    /// animations; `None` for grids, whose panels each have their own).
    pub projection: Option<Projection>,
}

/// The mapping of scene points to image pixels of a single-frame figure.
#[derive(Debug, Clone, PartialEq)]
pub struct Projection {
    cam: Camera,
    supersample: f64,
    x0: f64,
    y0: f64,
}

impl Projection {
    /// Pixel coordinates `(x, y)` (continuous: pixel `(i, j)` covers
    /// `[i, i + 1) x [j, j + 1)`) of the scene point `p` (m).
    pub fn pixel(&self, p: [f64; 3]) -> (f64, f64) {
        let v = self.cam.vertex(p, 0.0);
        (
            self.x0 + v.x / self.supersample,
            self.y0 + v.y / self.supersample,
        )
    }
}

/// The default output file in the output directory `dir`:
/// `render.png`, `render-grid.png` or `animation.gif`.
pub fn default_output(dir: &Path, layout: Layout) -> PathBuf {
    let dir = if dir.extension().is_some_and(|e| e == "pvd") {
        dir.parent().unwrap_or(Path::new(".")).to_owned()
    } else {
        dir.to_owned()
    };
    dir.join(match layout {
        Layout::Single => "render.png",
        Layout::Grid { .. } => "render-grid.png",
        Layout::Animation { .. } => "animation.gif",
    })
}

/// Renders the output directory `dir` (or its `fields.pvd`) as `opts` say
/// and writes the PNG or GIF.
///
/// # Errors
/// Any [`RenderError`]: unreadable or malformed files (naming them), a step
/// that was not written, an invalid option, a failed write.
pub fn render(dir: &Path, opts: &RenderOptions) -> Result<RenderReport> {
    check_options(opts)?;
    let out = opts
        .output
        .clone()
        .unwrap_or_else(|| default_output(dir, opts.layout));
    let ext = out
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    match opts.layout {
        Layout::Animation { frame_delay_ms } => {
            if ext != "gif" {
                return Err(RenderError::InvalidOption(format!(
                    "{}: an animation is written as a GIF (.gif)",
                    out.display()
                )));
            }
            let scene = Scene::load(dir, opts)?;
            let idx: Vec<usize> = (0..scene.frames.len()).collect();
            let layout = scene.single_layout(opts);
            let mut report = scene.report(opts, &idx);
            report.projection = Some(layout.projection(opts));
            crate::anim::write_gif(
                &out,
                opts.width,
                opts.height,
                frame_delay_ms,
                idx.len(),
                |k| scene.draw_single(opts, &layout, idx[k]),
            )?;
            report.output = Some(out);
            Ok(report)
        }
        _ => {
            if ext != "png" {
                return Err(RenderError::InvalidOption(format!(
                    "{}: renders are written as PNG (.png); use an animation for .gif",
                    out.display()
                )));
            }
            let (img, mut report) = render_image(dir, opts)?;
            img.write_png(&out)?;
            report.output = Some(out);
            Ok(report)
        }
    }
}

/// Renders a single frame or a grid into memory (an animation's first
/// frame for [`Layout::Animation`]).
///
/// # Errors
/// As [`render`], except for writing.
pub fn render_image(dir: &Path, opts: &RenderOptions) -> Result<(RgbImage, RenderReport)> {
    check_options(opts)?;
    let scene = Scene::load(dir, opts)?;
    let all: Vec<usize> = (0..scene.frames.len()).collect();
    match opts.layout {
        Layout::Grid { .. } => {
            let img = scene.draw_grid(opts);
            Ok((img, scene.report(opts, &all)))
        }
        _ => {
            let layout = scene.single_layout(opts);
            let img = scene.draw_single(opts, &layout, 0);
            let mut report = scene.report(opts, &[0]);
            report.projection = Some(layout.projection(opts));
            Ok((img, report))
        }
    }
}

/// The most memory a render's pixel buffers may take (bytes): the
/// supersampled colour and depth buffers (8 bytes a sample) and the image
/// (3 bytes a pixel). An image that would need more is refused before
/// anything is allocated, with the estimate, rather than aborting when the
/// allocation fails.
pub const MAX_RENDER_BYTES: u64 = 2 << 30;

/// The pixel buffers' bytes of a `width` x `height` image supersampled
/// `ss` times in each direction (see [`MAX_RENDER_BYTES`]).
pub fn render_bytes(width: u32, height: u32, ss: u32) -> u64 {
    let (w, h, ss) = (u64::from(width), u64::from(height), u64::from(ss));
    w * ss * h * ss * 8 + w * h * 3
}

fn check_options(opts: &RenderOptions) -> Result<()> {
    let bad = |m: String| Err(RenderError::InvalidOption(m));
    if !(160..=10_000).contains(&opts.width) || !(120..=10_000).contains(&opts.height) {
        return bad(format!(
            "image size {}x{}: width must be 160–10000 and height 120–10000 pixels",
            opts.width, opts.height
        ));
    }
    if !(1..=4).contains(&opts.supersample) {
        return bad(format!("supersample {}: must be 1–4", opts.supersample));
    }
    let bytes = render_bytes(opts.width, opts.height, opts.supersample);
    if bytes > MAX_RENDER_BYTES {
        return bad(format!(
            "image size {}x{}: its pixel buffers ({}x supersampled) would need about {:.1} GiB, above the bound of {} GiB; choose a smaller size",
            opts.width,
            opts.height,
            opts.supersample,
            bytes as f64 / f64::from(1u32 << 30),
            MAX_RENDER_BYTES >> 30
        ));
    }
    if let Layout::Grid { panels } = opts.layout
        && !(1..=24).contains(&panels)
    {
        return bad(format!("grid of {panels} panels: must be 1–24"));
    }
    if let Some((a, b)) = opts.range
        && !(a.is_finite() && b.is_finite() && a < b)
    {
        return bad(format!("range {a} .. {b}: need finite min < max"));
    }
    if let Some((i, c)) = opts.circles.iter().enumerate().find(|(_, c)| !c.is_valid()) {
        return bad(format!(
            "circle {i}: centre {:?}, normal {:?}, radius {}: need finite values, a normal and a positive radius",
            c.center, c.normal, c.radius
        ));
    }
    Ok(())
}

/// One sub-triangle of an element: node indices, the element, and which
/// edges (bit i: the edge opposite node i) lie on the element's boundary.
#[derive(Debug, Clone, Copy)]
struct SubTri {
    n: [usize; 3],
    cell: usize,
    edges: u8,
}

/// Grid position `(i, j)` on an element's reference triangle and the local
/// node there.
type NodeTable = [((usize, usize), usize)];

/// Splits every element into flat sub-triangles through its nodes: 1 for
/// T3, 4 for T6, 9 for T10.
fn sub_triangles(frame: &crate::vtu::Frame) -> Vec<SubTri> {
    // Grid position (i, j) on the element's reference triangle of order p
    // -> local node index (Gmsh/VTK order, see drape's vtu writer).
    const T6: [((usize, usize), usize); 6] = [
        ((0, 0), 0),
        ((2, 0), 1),
        ((0, 2), 2),
        ((1, 0), 3),
        ((1, 1), 4),
        ((0, 1), 5),
    ];
    const T10: [((usize, usize), usize); 10] = [
        ((0, 0), 0),
        ((3, 0), 1),
        ((0, 3), 2),
        ((1, 0), 3),
        ((2, 0), 4),
        ((2, 1), 5),
        ((1, 2), 6),
        ((0, 2), 7),
        ((0, 1), 8),
        ((1, 1), 9),
    ];
    let mut out = Vec::with_capacity(frame.cell_count() * 4);
    for c in 0..frame.cell_count() {
        let nodes = frame.cell(c);
        let (order, table): (usize, &NodeTable) = match frame.types[c] {
            VTK_QUADRATIC_TRIANGLE => (2, &T6),
            VTK_LAGRANGE_TRIANGLE => (3, &T10),
            _ => {
                out.push(SubTri {
                    n: [nodes[0], nodes[1], nodes[2]],
                    cell: c,
                    edges: 0b111,
                });
                continue;
            }
        };
        let at = |i: usize, j: usize| {
            let local = table
                .iter()
                .find(|(ij, _)| *ij == (i, j))
                .map(|(_, l)| *l)
                .expect("every grid point of the element has a node");
            nodes[local]
        };
        let on_boundary = |a: (usize, usize), b: (usize, usize)| {
            (a.1 == 0 && b.1 == 0)
                || (a.0 == 0 && b.0 == 0)
                || (a.0 + a.1 == order && b.0 + b.1 == order)
        };
        let mut push = |g: [(usize, usize); 3]| {
            let mut edges = 0u8;
            for i in 0..3 {
                if on_boundary(g[(i + 1) % 3], g[(i + 2) % 3]) {
                    edges |= 1 << i;
                }
            }
            out.push(SubTri {
                n: g.map(|(i, j)| at(i, j)),
                cell: c,
                edges,
            });
        };
        for j in 0..order {
            for i in 0..order - j {
                push([(i, j), (i + 1, j), (i, j + 1)]);
                if i + j + 2 <= order {
                    push([(i + 1, j), (i + 1, j + 1), (i, j + 1)]);
                }
            }
        }
    }
    out
}

/// One frame, loaded: positions, the field, sub-triangles, node normals.
struct Loaded {
    entry: FrameEntry,
    points: Vec<V3>,
    values: FieldValues,
    tris: Rc<Vec<SubTri>>,
    /// Connectivity and cell types the sub-triangles were made from.
    cells: Rc<(Vec<usize>, Vec<u8>)>,
    normals: Vec<V3>,
}

fn node_normals(points: &[V3], tris: &[SubTri]) -> Vec<V3> {
    let mut n = vec![[0.0; 3]; points.len()];
    for t in tris {
        let [a, b, c] = t.n.map(|i| points[i]);
        let f = cross(sub(b, a), sub(c, a));
        for &i in &t.n {
            n[i] = add(n[i], f);
        }
    }
    n.into_iter().map(normalize).collect()
}

/// Layout of a single-frame figure.
struct SingleLayout {
    m: Metrics,
    top: f32,
    band: f32,
    pw: usize,
    ph: usize,
    cam: Camera,
    edges: bool,
}

impl SingleLayout {
    fn projection(&self, opts: &RenderOptions) -> Projection {
        Projection {
            cam: self.cam.clone(),
            supersample: opts.supersample as f64,
            x0: self.m.pad as usize as f64,
            y0: self.top as usize as f64,
        }
    }
}

/// Everything a figure needs: the frames drawn, obstacles, colour scale.
struct Scene {
    title: String,
    frames: Vec<Loaded>,
    obstacles: Vec<Obstacle>,
    notices: Vec<String>,
    range: (f64, f64),
    cmap: ColorMap,
    region: Aabb,
    time_decimals: usize,
    /// The supersampled buffer, reused from frame to frame.
    buffer: std::cell::RefCell<Buffer>,
    /// Points round each of [`RenderOptions::circles`].
    circles: Vec<Vec<V3>>,
}

/// Sizes of the annotations of a figure `w` x `h`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Metrics {
    pub(crate) pad: f32,
    pub(crate) title_px: f32,
    pub(crate) sub_px: f32,
    pub(crate) label_px: f32,
}

impl Metrics {
    fn new(w: u32, h: u32) -> Self {
        let title_px = (h as f32 * 0.030).clamp(11.0, 44.0).min(w as f32 * 0.03);
        Self {
            pad: (w.min(h) as f32 * 0.02).max(4.0),
            title_px,
            sub_px: title_px * 0.72,
            label_px: title_px * 0.68,
        }
    }
}

impl Scene {
    fn load(dir: &Path, opts: &RenderOptions) -> Result<Self> {
        let out = OutputDir::open(dir)?;
        let indices = match opts.layout {
            Layout::Single => vec![out.select(opts.frame)?],
            Layout::Grid { panels } => out.spread(panels),
            Layout::Animation { .. } => (0..out.frames.len()).collect(),
        };
        let mut frames: Vec<Loaded> = Vec::with_capacity(indices.len());
        for &i in &indices {
            let entry = out.frames[i].clone();
            let frame = read_vtu(&entry.path)?;
            // Nothing can be drawn where a point has no position (a blank
            // image would say the fabric is not there), nor coloured by a
            // value that is not a number.
            frame.check_finite()?;
            let values = opts.field.extract(&frame)?;
            // Frames of one run share their mesh: split it once.
            let (tris, cells) = match frames.last() {
                Some(prev)
                    if prev.points.len() == frame.points.len()
                        && prev.cells.0 == frame.connectivity
                        && prev.cells.1 == frame.types =>
                {
                    (Rc::clone(&prev.tris), Rc::clone(&prev.cells))
                }
                _ => (
                    Rc::new(sub_triangles(&frame)),
                    Rc::new((frame.connectivity.clone(), frame.types.clone())),
                ),
            };
            let normals = node_normals(&frame.points, &tris);
            frames.push(Loaded {
                entry,
                points: frame.points,
                values,
                tris,
                cells,
                normals,
            });
        }

        let mut notices = Vec::new();
        let mut obstacles = Vec::new();
        if opts.obstacles {
            let scenario = opts
                .scenario
                .clone()
                .or_else(|| Some(out.dir.join("scenario.toml")).filter(|p| p.is_file()));
            if let Some(path) = scenario {
                let (o, n) = read_obstacles(&path)?;
                obstacles = o;
                notices.extend(n);
            }
        }

        let range = if opts.field.is_categorical() {
            (0.0, (WRINKLE_STATES.len() - 1) as f64)
        } else if let Some(r) = opts.range {
            r
        } else {
            let mut r: Option<(f64, f64)> = None;
            for f in &frames {
                if let Some((a, b)) = f.values.range() {
                    r = Some(r.map_or((a, b), |(x, y)| (x.min(a), y.max(b))));
                }
            }
            r.unwrap_or((0.0, 0.0))
        };
        let cmap = if opts.field.is_categorical() {
            ColorMap::wrinkle()
        } else {
            ColorMap::viridis(range.0, range.1)
        };

        let mut bbox = Aabb::empty();
        for f in &frames {
            for &p in &f.points {
                bbox.add(p);
            }
        }
        if bbox.is_empty() {
            bbox.add([0.0; 3]);
        }
        let e = bbox.extent();
        let margin = 0.3 * e[0].max(e[1]).max(e[2]).max(1e-9);
        let region = bbox.grown(margin);

        let t_end = out.frames.last().map_or(0.0, |f| f.time).abs();
        let time_decimals = if t_end > 0.0 && t_end < 0.01 {
            (3 - t_end.log10().floor() as i64).clamp(4, 12) as usize
        } else {
            4
        };
        Ok(Self {
            title: out.title,
            frames,
            obstacles,
            notices,
            range,
            cmap,
            region,
            time_decimals,
            buffer: std::cell::RefCell::new(Buffer::new(0, 0)),
            circles: opts.circles.iter().map(Circle::points).collect(),
        })
    }

    fn report(&self, opts: &RenderOptions, idx: &[usize]) -> RenderReport {
        RenderReport {
            output: None,
            width: opts.width,
            height: opts.height,
            frames: idx.iter().map(|&i| self.frames[i].entry.clone()).collect(),
            field: opts.field,
            range: self.range,
            colorbar_labels: self.colorbar(opts.field).labels(),
            caption: opts.field.label(),
            obstacles: self.obstacles.len(),
            notices: self.notices.clone(),
            projection: None,
        }
    }

    /// The colour bar of `field` on the scene's scale.
    fn colorbar(&self, field: Field) -> Colorbar<'_> {
        Colorbar {
            field,
            range: self.range,
            cmap: &self.cmap,
        }
    }

    fn time_label(&self, t: f64) -> String {
        format!("t = {:.*} s", self.time_decimals, t)
    }

    /// Obstacle triangles at time `t`.
    fn obstacle_tris(&self, t: f64) -> Vec<crate::geom::Tri> {
        self.obstacles
            .iter()
            .flat_map(|o| obstacle_triangles(o, t, &self.region))
            .collect()
    }

    /// Whether to outline the elements: as asked, or when their edges are
    /// on average at least 6 output pixels long (over every frame drawn, so
    /// that a grid or an animation decides once).
    fn edges(&self, opts: &RenderOptions, cam: &Camera) -> bool {
        if let Some(e) = opts.edges {
            return e;
        }
        let mut sum = 0.0;
        let mut n = 0usize;
        for f in &self.frames {
            // A sample of the triangles is enough for a mean.
            let step = (f.tris.len() / 4000).max(1);
            for t in f.tris.iter().step_by(step) {
                for k in 0..3 {
                    if t.edges & (1 << k) != 0 {
                        let a = cam.vertex(f.points[t.n[(k + 1) % 3]], 0.0);
                        let b = cam.vertex(f.points[t.n[(k + 2) % 3]], 0.0);
                        sum += ((a.x - b.x).powi(2) + (a.y - b.y).powi(2)).sqrt();
                        n += 1;
                    }
                }
            }
        }
        n > 0 && sum / n as f64 / opts.supersample as f64 >= 6.0
    }

    /// Width and height of the projection of the frames `which` and their
    /// obstacles (any unit: only their ratio matters).
    fn projected_extent(&self, view: View, which: &[usize]) -> (f64, f64) {
        let cam = self.camera(view, which, 1.0, 1.0);
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        let mut add = |p: V3| {
            let v = cam.vertex(p, 0.0);
            lo = [lo[0].min(v.x), lo[1].min(v.y)];
            hi = [hi[0].max(v.x), hi[1].max(v.y)];
        };
        for &i in which {
            let f = &self.frames[i];
            f.points.iter().for_each(|&p| add(p));
            for t in self.obstacle_tris(f.entry.time) {
                t.p.into_iter().for_each(&mut add);
            }
        }
        self.circles.iter().flatten().for_each(|&p| add(p));
        ((hi[0] - lo[0]).max(1e-9), (hi[1] - lo[1]).max(1e-9))
    }

    /// A camera for `view` fitted so that every frame in `which` and its
    /// obstacles fill a buffer of `w` x `h`.
    fn camera(&self, view: View, which: &[usize], w: f64, h: f64) -> Camera {
        let mut cam = Camera::new(view, &self.region);
        let mut pts: Vec<V3> = Vec::new();
        for &i in which {
            let f = &self.frames[i];
            pts.extend(f.points.iter().copied());
            for t in self.obstacle_tris(f.entry.time) {
                pts.extend(t.p);
            }
        }
        pts.extend(self.circles.iter().flatten().copied());
        cam.fit(pts.into_iter(), (0.0, 0.0, w, h));
        cam
    }

    /// Draws frame `i` with `cam` into a `w` x `h` image (supersampled by
    /// `ss`).
    fn draw_frame(
        &self,
        opts: &RenderOptions,
        cam: &Camera,
        edges: bool,
        i: usize,
        w: usize,
        h: usize,
    ) -> RgbImage {
        let ss = opts.supersample as usize;
        let f = &self.frames[i];
        let mut buf = self.buffer.borrow_mut();
        buf.reset(w * ss, h * ss);
        let verts: Vec<_> = f.points.iter().map(|&p| cam.vertex(p, 0.0)).collect();
        let style = Style {
            shading: opts.shading,
            edge_half_width: if edges { 0.35 * ss as f64 } else { 0.0 },
            light: cam.light,
        };
        // The fabric first: obstacle pixels behind it then fail the depth
        // test before they are shaded.
        for t in f.tris.iter() {
            let s = match &f.values {
                FieldValues::Point(v) => t.n.map(|i| v[i]),
                FieldValues::Cell(v) => [v[t.cell]; 3],
            };
            buf.draw(
                &RasterTri {
                    v: t.n.map(|i| verts[i]),
                    s,
                    n: t.n.map(|i| f.normals[i]),
                    paint: Paint::Field,
                    edges: t.edges,
                },
                &self.cmap,
                &style,
            );
        }
        // The tie-break of coplanar surfaces: obstacles are pushed back by
        // a depth bias, so that a fabric lying on a face — or a little
        // into it, as penalty contact leaves it — is drawn over it (and,
        // drawn first, it keeps the pixels of an exact tie).
        let bias = 3e-3 * self.region.diagonal();
        for t in self.obstacle_tris(f.entry.time) {
            let v = t.p.map(|p| cam.vertex(p, bias));
            buf.draw(
                &RasterTri {
                    v,
                    s: [0.0; 3],
                    n: [t.n; 3],
                    paint: Paint::Obstacle,
                    edges: 0,
                },
                &self.cmap,
                &style,
            );
        }
        let mut img = RgbImage::new(w as u32, h as u32);
        buf.downsample_into(ss, &mut img, 0, 0);
        img
    }

    /// Title lines; returns the height of the title band.
    fn draw_title(&self, img: &mut RgbImage, m: &Metrics, subtitle: &str) -> f32 {
        let y1 = m.pad + m.title_px * 0.95;
        text::draw(
            img,
            &self.title,
            (m.pad, y1),
            &text::Pen {
                px: m.title_px,
                weight: Weight::Bold,
                color: [20, 20, 20],
            },
            Align::Left,
        );
        let y2 = y1 + m.sub_px * 1.5;
        text::draw(
            img,
            subtitle,
            (m.pad, y2),
            &text::Pen {
                px: m.sub_px,
                weight: Weight::Regular,
                color: [60, 60, 60],
            },
            Align::Left,
        );
        y2 + m.pad * 0.8
    }

    /// Layout and camera of single-frame figures, shared by every frame of
    /// the scene (so that an animation keeps still).
    fn single_layout(&self, opts: &RenderOptions) -> SingleLayout {
        let (w, h) = (opts.width, opts.height);
        let m = Metrics::new(w, h);
        let top = m.pad + m.title_px * 0.95 + m.sub_px * 1.5 + m.pad * 0.8;
        let band = self.colorbar(opts.field).band_width(&m);
        let pw = (w as f32 - band - m.pad).max(16.0) as usize;
        let ph = (h as f32 - top - m.pad).max(16.0) as usize;
        let ss = opts.supersample as f64;
        let all: Vec<usize> = (0..self.frames.len()).collect();
        let cam = self.camera(opts.view, &all, pw as f64 * ss, ph as f64 * ss);
        let edges = self.edges(opts, &cam);
        SingleLayout {
            m,
            top,
            band,
            pw,
            ph,
            cam,
            edges,
        }
    }

    /// Frame `i` with title and colour bar.
    fn draw_single(&self, opts: &RenderOptions, l: &SingleLayout, i: usize) -> RgbImage {
        let (w, h) = (opts.width, opts.height);
        let mut img = RgbImage::new(w, h);
        let f = &self.frames[i];
        let mut subtitle = format!(
            "{}   ·   step {}   ·   {}   ·   {} view",
            self.time_label(f.entry.time),
            f.entry.step,
            opts.field.description(),
            opts.view.name()
        );
        if let Some(caption) = &opts.caption {
            subtitle.push_str("   ·   ");
            subtitle.push_str(caption);
        }
        self.draw_title(&mut img, &l.m, &subtitle);
        let panel = self.draw_frame(opts, &l.cam, l.edges, i, l.pw, l.ph);
        img.paste(&panel, l.m.pad as usize, l.top as usize);
        let projection = l.projection(opts);
        let width = (w.min(h) as f64 / 400.0).max(1.5);
        for (points, c) in self.circles.iter().zip(&opts.circles) {
            let pixels: Vec<(f64, f64)> = points.iter().map(|&p| projection.pixel(p)).collect();
            stroke(&mut img, &pixels, c.color, width, c.dashed);
        }
        let x0 = w as f32 - l.band;
        self.colorbar(opts.field)
            .draw(&mut img, &l.m, x0, l.top, h as f32 - l.m.pad);
        img
    }

    /// Every frame of the scene in a grid, one shared colour bar.
    fn draw_grid(&self, opts: &RenderOptions) -> RgbImage {
        let (w, h) = (opts.width, opts.height);
        let m = Metrics::new(w, h);
        let mut img = RgbImage::new(w, h);
        let n = self.frames.len();
        let last = &self.frames[n - 1].entry;
        let subtitle = format!(
            "{}   ·   {} view   ·   {} frames from t = 0 to {}",
            opts.field.description(),
            opts.view.name(),
            n,
            self.time_label(last.time).trim_start_matches("t = ")
        );
        let top = self.draw_title(&mut img, &m, &subtitle);
        let band = self.colorbar(opts.field).band_width(&m);
        let area_w = w as f32 - band - m.pad;
        let area_h = h as f32 - top - m.pad;
        // The number of columns that shows the figures largest.
        let all: Vec<usize> = (0..n).collect();
        let (du, dv) = self.projected_extent(opts.view, &all);
        let cap_h = m.sub_px * 1.5;
        let mut cols = 1;
        let mut best = 0.0;
        for c in 1..=n {
            let r = n.div_ceil(c);
            let pw = area_w as f64 / c as f64 - m.pad as f64 * 0.5;
            let ph = area_h as f64 / r as f64 - cap_h as f64 - m.pad as f64 * 0.5;
            let scale = (pw / du).min(ph / dv);
            if scale > best * 1.0001 {
                best = scale;
                cols = c;
            }
        }
        let rows = n.div_ceil(cols);
        let cell_w = area_w / cols as f32;
        let cell_h = area_h / rows as f32;
        let cap_px = m.sub_px;
        let pw = (cell_w - m.pad * 0.5).max(8.0) as usize;
        let ph = (cell_h - cap_h - m.pad * 0.5).max(8.0) as usize;
        let ss = opts.supersample as f64;
        let cam = self.camera(opts.view, &all, pw as f64 * ss, ph as f64 * ss);
        let edges = self.edges(opts, &cam);
        for (k, f) in self.frames.iter().enumerate() {
            let (r, c) = (k / cols, k % cols);
            let x = m.pad + c as f32 * cell_w;
            let y = top + r as f32 * cell_h;
            let label = format!("{}  (step {})", self.time_label(f.entry.time), f.entry.step);
            text::draw(
                &mut img,
                &label,
                (x + pw as f32 * 0.5, y + cap_px),
                &text::Pen {
                    px: cap_px,
                    weight: Weight::Regular,
                    color: [30, 30, 30],
                },
                Align::Center,
            );
            let panel = self.draw_frame(opts, &cam, edges, k, pw, ph);
            img.paste(&panel, x as usize, (y + cap_h) as usize);
            // A light frame around each panel.
            let (px0, py0) = (x as i64, (y + cap_h) as i64);
            let grey = [215, 215, 215];
            img.fill_rect(px0, py0, pw as i64, 1, grey);
            img.fill_rect(px0, py0 + ph as i64 - 1, pw as i64, 1, grey);
            img.fill_rect(px0, py0, 1, ph as i64, grey);
            img.fill_rect(px0 + pw as i64 - 1, py0, 1, ph as i64, grey);
        }
        let x0 = w as f32 - band;
        self.colorbar(opts.field)
            .draw(&mut img, &m, x0, top, h as f32 - m.pad);
        img
    }
}

#[cfg(test)]
mod tests {
    use crate::field::finite_range;

    #[test]
    fn finite_range_skips_nan() {
        assert_eq!(finite_range(&[1.0, f64::NAN, -2.0]), Some((-2.0, 1.0)));
        assert_eq!(finite_range(&[f64::NAN]), None);
    }
}
