//! The picture of a drape test (`drape test`'s `test.png`): the
//! specimens' shadows overlaid as a laboratory stacks its tracings, with
//! the pedestal and the specimen's circle, beside the histogram of their
//! fold counts.
//!
//! The caller measures (the crate does not depend on the library): it
//! hands over each specimen's outline in the horizontal plane's
//! coordinates about the pedestal's axis, the radii and the counts.

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::FontStyle;

use crate::error::{RenderError, Result};
use crate::plot::{SS, downsample, palette, register_fonts};

/// What the picture shows.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct TestFigure {
    /// The title (the scenario's).
    pub title: String,
    /// The line under it (the statistics).
    pub note: String,
    /// Each measured specimen's number and its shadow's outline: rings of
    /// points `(ξ, η)` in metres about the pedestal's axis.
    pub shadows: Vec<(usize, Vec<Vec<[f64; 2]>>)>,
    /// The pedestal's radius (m).
    pub pedestal_radius: f64,
    /// The specimen's radius (m).
    pub specimen_radius: f64,
    /// `(folds, specimens)`, ascending in folds.
    pub histogram: Vec<(usize, usize)>,
}

/// Draws `figure` into a PNG of `width` × `height` pixels at `out`.
///
/// # Errors
/// A size outside 320–10000 × 240–10000, a radius that is not positive
/// and finite, drawing or writing failures.
pub fn test_figure(figure: &TestFigure, out: &Path, width: u32, height: u32) -> Result<()> {
    if !(320..=10_000).contains(&width) || !(240..=10_000).contains(&height) {
        return Err(RenderError::InvalidOption(format!(
            "figure size {width}x{height}: width must be 320–10000 and height 240–10000 pixels"
        )));
    }
    let r = figure.specimen_radius.max(figure.pedestal_radius);
    if !(r.is_finite() && r > 0.0) {
        return Err(RenderError::InvalidOption(format!(
            "the specimen's radius {} m: a drape test's figure needs a positive radius",
            figure.specimen_radius
        )));
    }
    register_fonts();
    let (bw, bh) = (width * SS, height * SS);
    let mut buf = vec![255u8; bw as usize * bh as usize * 3];
    draw(&mut buf, (bw, bh), figure).map_err(|message| RenderError::Encode {
        path: out.to_owned(),
        message,
    })?;
    downsample(&buf, bw as usize, bh as usize, SS as usize).write_png(out)
}

fn draw(buf: &mut [u8], size: (u32, u32), f: &TestFigure) -> std::result::Result<(), String> {
    let e = |x: &dyn std::fmt::Display| x.to_string();
    let (w, h) = size;
    let u = (h.min(w / 2) as f64 / 800.0 / SS as f64).clamp(0.5, 4.0) * SS as f64;
    let px = |v: f64| (v * u).round().max(1.0) as u32;
    let root = BitMapBackend::with_buffer(buf, size).into_drawing_area();
    root.fill(&WHITE).map_err(|x| e(&x))?;
    let (top, rest) = root.split_vertically(px(74.0));
    let dark = RGBColor(20, 20, 20);
    top.draw(&Text::new(
        format!("{} — drape test", f.title),
        (px(16.0) as i32, px(12.0) as i32),
        ("sans-serif", px(22.0) as f64, FontStyle::Bold)
            .into_font()
            .color(&dark),
    ))
    .map_err(|x| e(&x))?;
    top.draw(&Text::new(
        f.note.clone(),
        (px(16.0) as i32, px(44.0) as i32),
        ("sans-serif", px(15.0) as f64)
            .into_font()
            .color(&RGBColor(30, 110, 50)),
    ))
    .map_err(|x| e(&x))?;
    let (left, right) = rest.split_horizontally(w / 2);
    shadows(&left, f, &px).map_err(|x| e(&x))?;
    histogram(&right, f, &px).map_err(|x| e(&x))?;
    root.present().map_err(|x| e(&x))?;
    Ok(())
}

/// The shadows in centimetres, one colour a specimen, over the pedestal
/// (solid) and the flat specimen's circle (dashed).
fn shadows<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    f: &TestFigure,
    px: &dyn Fn(f64) -> u32,
) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let dark = RGBColor(30, 30, 30);
    let reach = 100.0 * 1.08 * f.specimen_radius.max(f.pedestal_radius);
    // A square plotting area, so that a circle is round.
    let (aw, ah) = area.dim_in_pixel();
    let side = aw.min(ah);
    let area = area.margin(
        (ah - side) / 2,
        (ah - side) / 2,
        (aw - side) / 2,
        (aw - side) / 2,
    );
    let mut chart = ChartBuilder::on(&area)
        .caption(
            format!("Shadows of {} specimens (cm)", f.shadows.len()),
            ("sans-serif", px(17.0) as f64, FontStyle::Bold)
                .into_font()
                .color(&dark),
        )
        .margin(px(10.0))
        .x_label_area_size(px(40.0))
        .y_label_area_size(px(40.0))
        .build_cartesian_2d(-reach..reach, -reach..reach)?;
    chart
        .configure_mesh()
        .label_style(("sans-serif", px(13.0) as f64).into_font().color(&dark))
        .light_line_style(RGBColor(242, 242, 242))
        .bold_line_style(RGBColor(225, 225, 225))
        .draw()?;
    let circle = |radius: f64| -> Vec<(f64, f64)> {
        (0..=360)
            .map(|k| {
                let a = (k as f64).to_radians();
                (100.0 * radius * a.cos(), 100.0 * radius * a.sin())
            })
            .collect()
    };
    let grey = ShapeStyle {
        color: RGBColor(120, 120, 120).to_rgba(),
        filled: false,
        stroke_width: px(1.2),
    };
    chart.draw_series(DashedLineSeries::new(
        circle(f.specimen_radius),
        px(6.0),
        px(5.0),
        grey,
    ))?;
    for (i, (specimen, rings)) in f.shadows.iter().enumerate() {
        let style = ShapeStyle {
            color: palette(i).to_rgba(),
            filled: false,
            stroke_width: px(1.6),
        };
        for ring in rings {
            let mut points: Vec<(f64, f64)> =
                ring.iter().map(|p| (100.0 * p[0], 100.0 * p[1])).collect();
            if let Some(&first) = points.first() {
                points.push(first);
            }
            // Segment by segment: plotters' thick polylines spike at sharp
            // turns (see `plot`).
            let anno = chart.draw_series(
                points
                    .windows(2)
                    .map(|w| PathElement::new(vec![w[0], w[1]], style)),
            )?;
            if ring.as_ptr() == rings[0].as_ptr() {
                let len = px(18.0) as i32;
                anno.label(format!("specimen {specimen:04}"))
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + len, y)], style));
            }
        }
    }
    chart.draw_series(std::iter::once(PathElement::new(
        circle(f.pedestal_radius),
        ShapeStyle {
            color: dark.to_rgba(),
            filled: false,
            stroke_width: px(1.6),
        },
    )))?;
    if !f.shadows.is_empty() && f.shadows.len() <= 12 {
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .background_style(WHITE.mix(0.85))
            .border_style(RGBColor(190, 190, 190))
            .label_font(("sans-serif", px(12.0) as f64).into_font().color(&dark))
            .margin(px(6.0))
            .draw()?;
    }
    Ok(())
}

/// Specimens by fold count, one bar a count.
fn histogram<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    f: &TestFigure,
    px: &dyn Fn(f64) -> u32,
) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let dark = RGBColor(30, 30, 30);
    let lo = f.histogram.first().map_or(0, |h| h.0).saturating_sub(1);
    let hi = f.histogram.last().map_or(10, |h| h.0) + 1;
    let most = f.histogram.iter().map(|h| h.1).max().unwrap_or(1);
    let mut chart = ChartBuilder::on(area)
        .caption(
            "Fold counts",
            ("sans-serif", px(17.0) as f64, FontStyle::Bold)
                .into_font()
                .color(&dark),
        )
        .margin(px(14.0))
        .margin_right(px(24.0))
        .x_label_area_size(px(44.0))
        .y_label_area_size(px(50.0))
        .build_cartesian_2d(lo as f64 - 0.5..hi as f64 + 0.5, 0.0..most as f64 + 0.5)?;
    let int = |v: &f64| format!("{}", v.round() as i64);
    chart
        .configure_mesh()
        .x_desc("folds")
        .y_desc("specimens")
        .x_labels((hi - lo + 1).min(30))
        .y_labels((most + 1).min(20))
        .x_label_formatter(&int)
        .y_label_formatter(&int)
        .label_style(("sans-serif", px(13.0) as f64).into_font().color(&dark))
        .axis_desc_style(("sans-serif", px(14.0) as f64).into_font().color(&dark))
        .light_line_style(RGBColor(242, 242, 242))
        .bold_line_style(RGBColor(225, 225, 225))
        .draw()?;
    chart.draw_series(f.histogram.iter().map(|&(folds, count)| {
        let x = folds as f64;
        Rectangle::new(
            [(x - 0.38, 0.0), (x + 0.38, count as f64)],
            palette(0).mix(0.85).filled(),
        )
    }))?;
    Ok(())
}
