//! Time histories of `history.csv` as line plots (plotters, bitmap backend,
//! drawn at twice the size and box-filtered down for anti-aliased lines).

use std::path::{Path, PathBuf};
use std::sync::Once;

use plotters::coord::Shift;
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use plotters::style::FontStyle;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use crate::colormap::WRINKLE_COLOURS;
use crate::error::{RenderError, Result};
use crate::field::format_value;
use crate::image::RgbImage;
use crate::outdir::History;

/// What [`plot`] drew.
#[derive(Debug, Clone, PartialEq)]
pub struct PlotReport {
    /// The file written (`None` from [`plot_image`]).
    pub output: Option<PathBuf>,
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Rows of `history.csv` plotted.
    pub rows: usize,
    /// Titles of the panels, in reading order.
    pub panels: Vec<String>,
    /// Names of the monitors plotted.
    pub monitors: Vec<String>,
    /// The line under the title: `summary.json`'s message when the run
    /// ended at rest (`"at_rest": true`), else `None`.
    pub note: Option<String>,
}

/// Supersampling: drawn at twice the size, box-filtered down.
pub(crate) const SS: u32 = 2;

/// The embedded DejaVu Sans as plotters' "sans-serif" (once a process).
pub(crate) fn register_fonts() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // The embedded fonts are checked to parse by a test; a failure here
        // would only leave plotters without text.
        let _ = plotters::style::register_font(
            "sans-serif",
            FontStyle::Normal,
            crate::text::REGULAR_BYTES,
        );
        let _ =
            plotters::style::register_font("sans-serif", FontStyle::Bold, crate::text::BOLD_BYTES);
    });
}

/// A panel of values the caller computed at times of its own — one a
/// frame, say: a drape tester's drape coefficient and folds — drawn after
/// the history's panels by [`plot_with`].
#[derive(Debug, Clone, PartialEq)]
pub struct ExtraPanel {
    /// The panel's title.
    pub title: String,
    /// The y axis' label, with its unit.
    pub y_label: String,
    /// Times (s) of the values.
    pub time: Vec<f64>,
    /// Named series, one value a time.
    pub series: Vec<(String, Vec<f64>)>,
    /// Whole numbers (a count): integer ticks from 0.
    pub integer: bool,
}

/// Plots the history of the output directory `dir` to the PNG `out`:
/// monitored z, energies, Newton iterations, contact force, wrinkling state
/// fractions and the smallest gap, against time.
///
/// # Errors
/// [`RenderError::Io`] / [`RenderError::Format`] for a missing or malformed
/// `history.csv`, [`RenderError::InvalidOption`] for a bad size or an
/// output that is not `.png`, [`RenderError::Encode`] if drawing fails.
pub fn plot(dir: &Path, out: &Path, width: u32, height: u32) -> Result<PlotReport> {
    plot_with(dir, out, width, height, &[])
}

/// As [`plot`], with the panels `extra` after the history's (two a row).
///
/// # Errors
/// As [`plot`].
pub fn plot_with(
    dir: &Path,
    out: &Path,
    width: u32,
    height: u32,
    extra: &[ExtraPanel],
) -> Result<PlotReport> {
    let ext = out
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    if ext != "png" {
        return Err(RenderError::InvalidOption(format!(
            "{}: plots are written as PNG (.png)",
            out.display()
        )));
    }
    let (img, mut report) = plot_image_with(dir, width, height, extra)?;
    img.write_png(out)?;
    report.output = Some(out.to_owned());
    Ok(report)
}

/// The columns every history drape writes has, whatever the scenario.
pub const HISTORY_COLUMNS: [&str; 9] = [
    "step",
    "time",
    "dt",
    "iterations",
    "kinetic_energy",
    "strain_energy",
    "active_contacts",
    "contact_force",
    "min_gap",
];

/// Refuses a history the plot cannot interpret: one without a column of
/// [`HISTORY_COLUMNS`], or without the columns of a monitor that
/// `dir/scenario.toml` names (its panel would say there is none).
fn check_columns(dir: &Path, hist: &History) -> Result<()> {
    let mut missing: Vec<String> = HISTORY_COLUMNS
        .iter()
        .filter(|c| hist.column(c).is_none())
        .map(|c| (*c).to_owned())
        .collect();
    let monitors = std::fs::read_to_string(dir.join("scenario.toml"))
        .map(|text| crate::scenario::monitor_names(&text))
        .unwrap_or_default();
    for name in monitors {
        for c in ["x", "y", "z"] {
            let column = format!("{name}_{c}");
            if hist.column(&column).is_none() {
                missing.push(column);
            }
        }
    }
    if missing.is_empty() {
        return Ok(());
    }
    Err(RenderError::format(
        dir.join("history.csv"),
        format!(
            "lacks the column(s) {} (a drape history has {}, and a monitor's <name>_x, _y, _z for each [[monitor]] of scenario.toml): nothing to plot it by",
            missing.join(", "),
            HISTORY_COLUMNS.join(", ")
        ),
    ))
}

/// As [`plot`], into memory.
///
/// # Errors
/// As [`plot`], except for writing.
pub fn plot_image(dir: &Path, width: u32, height: u32) -> Result<(RgbImage, PlotReport)> {
    plot_image_with(dir, width, height, &[])
}

/// As [`plot_with`], into memory.
///
/// # Errors
/// As [`plot`], except for writing.
pub fn plot_image_with(
    dir: &Path,
    width: u32,
    height: u32,
    extra: &[ExtraPanel],
) -> Result<(RgbImage, PlotReport)> {
    if !(320..=10_000).contains(&width) || !(240..=10_000).contains(&height) {
        return Err(RenderError::InvalidOption(format!(
            "plot size {width}x{height}: width must be 320–10000 and height 240–10000 pixels"
        )));
    }
    let dir = output_dir(dir)?;
    let hist = History::read(dir)?;
    let path = dir.join("history.csv");
    check_columns(dir, &hist)?;
    let time = hist
        .column("time")
        .ok_or_else(|| RenderError::format(&path, "no time column"))?
        .to_vec();
    if time.is_empty() {
        return Err(RenderError::format(&path, "no rows to plot"));
    }
    let (title, note) = title_and_note(dir);
    register_fonts();
    let monitors = hist.monitors();
    let tension_field = std::fs::read_to_string(dir.join("scenario.toml"))
        .ok()
        .and_then(|text| crate::scenario::has_tension_field(&text));
    let mut panels = history_panels(&hist, &monitors, tension_field);
    panels.extend(extra.iter().map(extra_panel));
    let titles: Vec<String> = panels.iter().map(|p| p.title.clone()).collect();
    let (bw, bh) = (width * SS, height * SS);
    let mut buf = vec![255u8; bw as usize * bh as usize * 3];
    let heading = Heading {
        title: &title,
        note: note.as_deref(),
    };
    draw_all(&mut buf, (bw, bh), &heading, &time, &panels).map_err(|message| {
        RenderError::Encode {
            path: dir.join("history.csv"),
            message,
        }
    })?;
    let img = downsample(&buf, bw as usize, bh as usize, SS as usize);
    let report = PlotReport {
        output: None,
        width,
        height,
        rows: time.len(),
        panels: titles,
        monitors,
        note,
    };
    Ok((img, report))
}

/// The output directory `dir` names (the directory of a `.pvd` given
/// instead), which must be a directory.
fn output_dir(dir: &Path) -> Result<&Path> {
    let dir = if dir.extension().is_some_and(|e| e == "pvd") {
        dir.parent().unwrap_or(Path::new("."))
    } else {
        dir
    };
    crate::outdir::require_dir(dir)?;
    Ok(dir)
}

/// The figure's title (the summary's, else the directory's name) and
/// its note: the summary's message when the run ended at rest.
fn title_and_note(dir: &Path) -> (String, Option<String>) {
    let summary = std::fs::read_to_string(dir.join("summary.json"))
        .ok()
        .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok());
    let note = summary
        .as_ref()
        .filter(|v| v.get("at_rest").and_then(serde_json::Value::as_bool) == Some(true))
        .and_then(|v| v.get("message")?.as_str().map(str::to_owned));
    let title = summary
        .as_ref()
        .and_then(|v| v.get("title")?.as_str().map(str::to_owned))
        .unwrap_or_else(|| {
            dir.file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default()
        });
    (title, note)
}

/// The panels of a history, in order: the monitors' heights, the
/// energies, Newton's iterations, the contact force, the wrinkling state
/// (labelled for a material with or without a tension field, when the
/// scenario says which) and the smallest gap; with `[[cavity]]` columns
/// (`cavity<i>_...`), the cavities' pressure, volume and gas mass.
fn history_panels(hist: &History, monitors: &[String], tension_field: Option<bool>) -> Vec<Panel> {
    let has_obstacles = column(hist, "min_gap").is_some_and(|v| v.iter().any(|x| x.is_finite()));
    let mut panels = vec![
        monitor_panel(hist, monitors),
        energy_panel(hist),
        iteration_panel(hist),
        contact_force_panel(hist, has_obstacles),
        wrinkling_panel(hist, tension_field),
        gap_panel(hist, has_obstacles),
    ];
    panels.extend(cavity_panels(hist));
    panels
}

/// With cavities: each cavity's absolute pressure, volume and gas mass
/// (with its inflow and vent outflow where an inflator or vents moved
/// gas), one panel each; none without.
fn cavity_panels(hist: &History) -> Vec<Panel> {
    let count = (0..)
        .take_while(|i| hist.column(&format!("cavity{i}_pressure")).is_some())
        .count();
    if count == 0 {
        return Vec::new();
    }
    let mut panels = vec![
        Panel::new("Cavities: gas pressure (absolute)", "pressure (Pa)"),
        Panel::new("Cavities: volume", "volume (m³)"),
        Panel::new("Cavities: gas mass", "mass (kg)"),
    ];
    for i in 0..count {
        for (panel, (suffix, label)) in panels.iter_mut().zip([
            ("pressure", format!("cavity {i}")),
            ("volume", format!("cavity {i}")),
            ("mass", format!("cavity {i}")),
        ]) {
            if let Some(v) = column(hist, &format!("cavity{i}_{suffix}")) {
                panel.series.push(Series::line(&label, v, palette(i)));
            }
        }
        for (k, flow) in ["inflow", "outflow"].iter().enumerate() {
            if let Some(v) = column(hist, &format!("cavity{i}_{flow}"))
                && v.iter().any(|&x| x != 0.0)
            {
                let mut s =
                    Series::line(&format!("cavity {i} {flow}"), v, palette(count + 2 * i + k));
                s.dashed = k == 1;
                s.points = k == 0;
                panels[2].series.push(s);
            }
        }
    }
    panels
}

/// The column `name` of `hist`, if it has one.
fn column(hist: &History, name: &str) -> Option<Vec<f64>> {
    hist.column(name).map(<[f64]>::to_vec)
}

fn monitor_panel(hist: &History, monitors: &[String]) -> Panel {
    let mut mon = Panel::new("Monitored nodes: height", "z (m)");
    for (k, name) in monitors.iter().enumerate() {
        if let Some(z) = column(hist, &format!("{name}_z")) {
            mon.series.push(Series::line(name, z, palette(k)));
        }
    }
    if mon.series.is_empty() {
        mon.empty_note = Some("no [[monitor]] in the scenario".to_owned());
    }
    mon
}

fn energy_panel(hist: &History) -> Panel {
    let mut en = Panel::new("Energies", "energy (J)");
    for (k, (c, label)) in [
        ("kinetic_energy", "kinetic"),
        ("strain_energy", "strain"),
        ("contact_energy", "contact (penalty)"),
        ("external_work", "work of the loads"),
        ("total_energy", "total = K + U + C − W"),
    ]
    .iter()
    .enumerate()
    {
        if let Some(v) = column(hist, c) {
            if *c == "contact_energy" && v.iter().all(|&x| x == 0.0) {
                continue;
            }
            let mut s = Series::line(label, v, palette(k));
            if *c == "total_energy" {
                s.dashed = true;
                s.color = RGBColor(30, 30, 30);
            }
            en.series.push(s);
        }
    }
    en
}

fn iteration_panel(hist: &History) -> Panel {
    let mut it = Panel::new("Newton iterations per step", "iterations");
    if let Some(step) = column(hist, "step") {
        it.x = Some(("step", step));
    }
    if let Some(v) = column(hist, "iterations") {
        let mut s = Series::line("iterations", v, palette(0));
        s.points = true;
        it.series.push(s);
        it.integer_y = true;
    }
    if let Some(c) = column(hist, "cutbacks")
        && c.iter().any(|&x| x > 0.0)
    {
        it.series.push(Series {
            name: "cutbacks (step halvings)".to_owned(),
            values: c,
            color: RGBColor(214, 39, 40),
            dashed: false,
            points: true,
            skip_zero: true,
        });
    }
    it.legend = it.series.len() > 1;
    it
}

fn contact_force_panel(hist: &History, has_obstacles: bool) -> Panel {
    let mut cf = Panel::new("Contact force (resultant on the fabric)", "force (N)");
    match column(hist, "contact_force") {
        Some(v) if has_obstacles => cf.series.push(Series::line("contact force", v, palette(0))),
        _ => cf.empty_note = Some("no obstacles".to_owned()),
    }
    cf.legend = false;
    cf
}

/// The fractions of taut, wrinkled and slack elements. Without a
/// tension-field model the fabric carries compression and nothing
/// wrinkles: the states then classify the principal stresses (both >= 0,
/// one < 0, both <= 0: where the fabric would wrinkle), and the panel
/// says so.
fn wrinkling_panel(hist: &History, tension_field: Option<bool>) -> Panel {
    let (title, labels) = if tension_field == Some(false) {
        (
            "Stress state, no tension-field model (fraction of elements)",
            [
                "tension both ways",
                "compression one way (would wrinkle)",
                "compression both ways",
            ],
        )
    } else {
        (
            "Wrinkling state (fraction of elements)",
            ["taut", "wrinkled", "slack"],
        )
    };
    let mut ws = Panel::new(title, "fraction");
    for (k, (c, label)) in ["taut_fraction", "wrinkled_fraction", "slack_fraction"]
        .iter()
        .zip(labels)
        .enumerate()
    {
        if let Some(v) = column(hist, c) {
            let [r, g, b] = WRINKLE_COLOURS[k];
            ws.series.push(Series::line(label, v, RGBColor(r, g, b)));
        }
    }
    ws.fixed_y = Some((0.0, 1.0));
    if ws.series.is_empty() {
        ws.empty_note = Some("no state fractions in history.csv".to_owned());
    }
    ws
}

fn gap_panel(hist: &History, has_obstacles: bool) -> Panel {
    let mut gap = Panel::new("Smallest gap to an obstacle", "gap (m)");
    if let Some(v) = column(hist, "min_gap")
        && has_obstacles
    {
        gap.series.push(Series::line("min gap", v, palette(0)));
        gap.zero_line = true;
    } else {
        gap.empty_note = Some("no obstacles".to_owned());
    }
    gap.legend = false;
    gap
}

/// A caller's panel against time.
fn extra_panel(e: &ExtraPanel) -> Panel {
    let mut p = Panel::new(&e.title, &e.y_label);
    p.x = Some(("time (s)", e.time.clone()));
    for (k, (name, values)) in e.series.iter().enumerate() {
        p.series
            .push(Series::line(name, values.clone(), palette(k)));
    }
    p.integer_y = e.integer;
    p.legend = e.series.len() > 1;
    p
}

/// Tableau's ten colours, round.
pub(crate) fn palette(k: usize) -> RGBColor {
    let c = colorous::TABLEAU10[k % colorous::TABLEAU10.len()];
    RGBColor(c.r, c.g, c.b)
}

struct Series {
    name: String,
    values: Vec<f64>,
    color: RGBColor,
    dashed: bool,
    /// Dots instead of a line.
    points: bool,
    /// Leave zeros out (dots only).
    skip_zero: bool,
}

impl Series {
    fn line(name: &str, values: Vec<f64>, color: RGBColor) -> Self {
        Self {
            name: name.to_owned(),
            values,
            color,
            dashed: false,
            points: false,
            skip_zero: false,
        }
    }
}

struct Panel {
    title: String,
    /// Abscissa other than time: its name and values.
    x: Option<(&'static str, Vec<f64>)>,
    y_desc: String,
    series: Vec<Series>,
    legend: bool,
    integer_y: bool,
    zero_line: bool,
    fixed_y: Option<(f64, f64)>,
    empty_note: Option<String>,
}

impl Panel {
    fn new(title: &str, y_desc: &str) -> Self {
        Self {
            title: title.to_owned(),
            x: None,
            y_desc: y_desc.to_owned(),
            series: Vec::new(),
            legend: true,
            integer_y: false,
            zero_line: false,
            fixed_y: None,
            empty_note: None,
        }
    }
}

fn y_range(p: &Panel) -> (f64, f64) {
    if let Some(r) = p.fixed_y {
        return (r.0 - 0.02, r.1 + 0.02);
    }
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for s in &p.series {
        for &v in &s.values {
            if v.is_finite() {
                lo = lo.min(v);
                hi = hi.max(v);
            }
        }
    }
    if p.zero_line {
        lo = lo.min(0.0);
        hi = hi.max(0.0);
    }
    if p.integer_y {
        return (0.0, (hi.max(1.0) + 1.0).ceil());
    }
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    if hi - lo <= 1e-300 || hi - lo <= 1e-12 * hi.abs().max(lo.abs()) {
        let d = if lo == 0.0 { 1.0 } else { 0.1 * lo.abs() };
        return (lo - d, hi + d);
    }
    let pad = 0.06 * (hi - lo);
    (lo - pad, hi + pad)
}

/// The most y ticks a panel asks plotters for: 6, or for a count (whole
/// numbers) no more than the whole numbers in its range, so that plotters'
/// step (1, 2 or 5 times a power of ten, the finest that gives no more
/// ticks than asked) is never below 1 — at 0 to 3 folds six ticks were
/// 0, 0.5, 1, … and printed "0, 1, 1, 2, 2".
fn y_label_count(p: &Panel, (y0, y1): (f64, f64)) -> usize {
    const MOST: usize = 6;
    if p.integer_y {
        // y_range gives a count's panel whole-number ends, 0 to at least 2.
        let whole = (y1 - y0).floor();
        if whole.is_finite() && whole >= 1.0 && whole < MOST as f64 {
            return whole as usize + 1;
        }
    }
    MOST
}

/// What the plot's title area says: the title, and a note under it.
struct Heading<'a> {
    title: &'a str,
    note: Option<&'a str>,
}

fn draw_all(
    buf: &mut [u8],
    size: (u32, u32),
    heading: &Heading,
    time: &[f64],
    panels: &[Panel],
) -> std::result::Result<(), String> {
    let e = |x: &dyn std::fmt::Display| x.to_string();
    let (w, h) = size;
    let u = (h.min(w * 3 / 4) as f64 / 900.0 / SS as f64).clamp(0.5, 4.0) * SS as f64;
    let px = |v: f64| (v * u).round().max(1.0) as u32;
    let root = BitMapBackend::with_buffer(buf, size).into_drawing_area();
    root.fill(&WHITE).map_err(|x| e(&x))?;
    let title_h = px(if heading.note.is_some() { 70.0 } else { 46.0 });
    let (top, rest) = root.split_vertically(title_h);
    top.draw(&Text::new(
        format!("{} — time histories", heading.title),
        (px(16.0) as i32, px(12.0) as i32),
        ("sans-serif", px(22.0) as f64, FontStyle::Bold)
            .into_font()
            .color(&RGBColor(20, 20, 20)),
    ))
    .map_err(|x| e(&x))?;
    if let Some(note) = heading.note {
        top.draw(&Text::new(
            note.to_owned(),
            (px(16.0) as i32, px(42.0) as i32),
            ("sans-serif", px(15.0) as f64)
                .into_font()
                .color(&RGBColor(30, 110, 50)),
        ))
        .map_err(|x| e(&x))?;
    }
    let areas = rest.split_evenly((panels.len().div_ceil(2).max(1), 2));
    for (area, p) in areas.iter().zip(panels) {
        let (x_desc, x) = match &p.x {
            Some((name, v)) => (*name, v.as_slice()),
            None => ("time (s)", time),
        };
        draw_panel(area, p, x_desc, x, &px).map_err(|x| e(&x))?;
    }
    root.present().map_err(|x| e(&x))?;
    Ok(())
}

fn draw_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    p: &Panel,
    x_desc: &str,
    time: &[f64],
    px: &dyn Fn(f64) -> u32,
) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let (y0, y1) = y_range(p);
    let (t0, t1) = match crate::field::finite_range(time) {
        Some((a, b)) if b > a => (a, b),
        Some((a, _)) => (a, a + 1.0),
        None => (0.0, 1.0),
    };
    let dark = RGBColor(30, 30, 30);
    let mut chart = ChartBuilder::on(area)
        .caption(
            &p.title,
            ("sans-serif", px(17.0) as f64, FontStyle::Bold)
                .into_font()
                .color(&dark),
        )
        .margin(px(10.0))
        .margin_right(px(22.0))
        .x_label_area_size(px(44.0))
        .y_label_area_size(px(78.0))
        .build_cartesian_2d(t0..t1, y0..y1)?;
    let label_font = ("sans-serif", px(13.0) as f64).into_font().color(&dark);
    let desc_font = ("sans-serif", px(14.0) as f64).into_font().color(&dark);
    // Tick values that are round-off away from zero print as 0.
    let x_fmt = |v: &f64| format_value(snap(*v, t1 - t0));
    let y_fmt = |v: &f64| format_value(snap(*v, y1 - y0));
    let int_fmt = |v: &f64| format!("{}", v.round() as i64);
    let mut mesh = chart.configure_mesh();
    mesh.x_desc(x_desc)
        .y_desc(p.y_desc.as_str())
        .label_style(label_font.clone())
        .axis_desc_style(desc_font)
        .x_labels(7)
        .y_labels(y_label_count(p, (y0, y1)))
        .x_label_formatter(&x_fmt)
        .light_line_style(RGBColor(240, 240, 240))
        .bold_line_style(RGBColor(222, 222, 222))
        .axis_style(ShapeStyle {
            color: RGBColor(90, 90, 90).to_rgba(),
            filled: false,
            stroke_width: px(1.0),
        });
    if p.integer_y {
        mesh.y_label_formatter(&int_fmt);
    } else {
        mesh.y_label_formatter(&y_fmt);
    }
    mesh.draw()?;
    if p.zero_line && y0 < 0.0 && y1 > 0.0 {
        chart.draw_series(std::iter::once(PathElement::new(
            vec![(t0, 0.0), (t1, 0.0)],
            ShapeStyle {
                color: RGBColor(150, 150, 150).to_rgba(),
                filled: false,
                stroke_width: px(1.0),
            },
        )))?;
    }
    draw_series(&mut chart, p, time, px)?;
    if p.legend && !p.series.is_empty() {
        chart
            .configure_series_labels()
            .position(legend_corner(p, time, (t0, t1), (y0, y1)))
            .background_style(WHITE.mix(0.85))
            .border_style(RGBColor(190, 190, 190))
            .label_font(label_font)
            .legend_area_size(px(30.0) as i32)
            .margin(px(8.0))
            .draw()?;
    }
    if let Some(note) = &p.empty_note {
        let style = ("sans-serif", px(15.0) as f64)
            .into_font()
            .color(&RGBColor(120, 120, 120))
            .pos(Pos::new(HPos::Center, VPos::Center));
        chart.plotting_area().draw(&Text::new(
            note.clone(),
            (0.5 * (t0 + t1), 0.5 * (y0 + y1)),
            style,
        ))?;
    }
    Ok(())
}

/// The series of panel `p` against `time` on `chart`: dots, a dashed
/// line or a solid one, each with its legend entry.
fn draw_series<DB: DrawingBackend>(
    chart: &mut ChartContext<'_, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
    p: &Panel,
    time: &[f64],
    px: &dyn Fn(f64) -> u32,
) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let stroke = px(1.8);
    for s in &p.series {
        let style = ShapeStyle {
            color: s.color.to_rgba(),
            filled: false,
            stroke_width: stroke,
        };
        let pts: Vec<(f64, f64)> = time
            .iter()
            .zip(&s.values)
            .filter(|(t, v)| t.is_finite() && v.is_finite())
            .map(|(&t, &v)| (t, v))
            .collect();
        let legend_style = style;
        // Polylines are drawn segment by segment: plotters joins thick
        // polylines with unbounded miters, which spike out of the panel at
        // sharp turns.
        let anno = if s.points {
            let r = px(1.6);
            chart.draw_series(
                pts.iter()
                    .filter(|(_, v)| !s.skip_zero || *v != 0.0)
                    .map(|&(t, v)| Circle::new((t, v), r, style.filled())),
            )?
        } else if s.dashed {
            chart.draw_series(DashedLineSeries::new(pts, px(7.0), px(5.0), style))?
        } else {
            chart.draw_series(
                pts.windows(2)
                    .map(|w| PathElement::new(vec![w[0], w[1]], style)),
            )?
        };
        let len = px(22.0) as i32;
        anno.label(s.name.as_str())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + len, y)], legend_style));
    }
    Ok(())
}

/// `v`, or 0 if it is round-off next to the axis span `span`.
fn snap(v: f64, span: f64) -> f64 {
    if v.abs() < 1e-9 * span.abs() { 0.0 } else { v }
}

/// The corner of the plot with the fewest data points under a legend-sized
/// box.
fn legend_corner(
    p: &Panel,
    x: &[f64],
    (x0, x1): (f64, f64),
    (y0, y1): (f64, f64),
) -> SeriesLabelPosition {
    let (bw, bh) = (0.38, 0.12 + 0.09 * p.series.len() as f64);
    let corners = [
        (SeriesLabelPosition::UpperRight, 1.0 - bw, 1.0 - bh),
        (SeriesLabelPosition::UpperLeft, 0.0, 1.0 - bh),
        (SeriesLabelPosition::LowerRight, 1.0 - bw, 0.0),
        (SeriesLabelPosition::LowerLeft, 0.0, 0.0),
    ];
    let mut best = (usize::MAX, SeriesLabelPosition::UpperRight);
    for (pos, cx, cy) in corners {
        let mut hits = 0;
        for s in &p.series {
            for (&t, &v) in x.iter().zip(&s.values) {
                let u = (t - x0) / (x1 - x0);
                let w = (v - y0) / (y1 - y0);
                if u >= cx - 0.02 && u <= cx + bw + 0.02 && w >= cy - 0.02 && w <= cy + bh + 0.02 {
                    hits += 1;
                }
            }
        }
        if hits < best.0 {
            best = (hits, pos);
        }
    }
    best.1
}

/// `buf` (RGB, `w` × `h`) box-filtered down by `f` in each direction.
pub(crate) fn downsample(buf: &[u8], w: usize, h: usize, f: usize) -> RgbImage {
    let (ow, oh) = (w / f, h / f);
    let mut img = RgbImage::new(ow as u32, oh as u32);
    let n = (f * f) as u32;
    for y in 0..oh {
        for x in 0..ow {
            let mut acc = [0u32; 3];
            for sy in 0..f {
                for sx in 0..f {
                    let i = 3 * ((y * f + sy) * w + x * f + sx);
                    for k in 0..3 {
                        acc[k] += buf[i + k] as u32;
                    }
                }
            }
            img.put(x, y, acc.map(|a| ((a + n / 2) / n) as u8));
        }
    }
    img
}

#[cfg(test)]
mod tests {
    use super::*;
    use plotters::coord::ranged1d::Ranged;

    /// Issue 46: a count's panel (folds, Newton iterations) has whole-number
    /// ticks only, each printed once, whatever the largest count; plotters'
    /// own choice of ticks is what is checked.
    #[test]
    fn a_counts_ticks_are_whole_numbers() {
        for most in 0..=60 {
            let mut p = Panel::new("Folds", "folds");
            p.series
                .push(Series::line("folds", vec![0.0, most as f64], palette(0)));
            p.integer_y = true;
            let (y0, y1) = y_range(&p);
            let axis: RangedCoordf64 = (y0..y1).into();
            let ticks = axis.key_points(y_label_count(&p, (y0, y1)));
            assert!(ticks.len() >= 2, "{most}: {ticks:?}");
            assert!(
                ticks.iter().all(|t| t.fract() == 0.0),
                "{most} folds: ticks {ticks:?}"
            );
        }
    }
}
