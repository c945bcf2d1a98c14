//! `drape measure DIR`: the shadow, drape coefficient and folds of a frame
//! of a drape-tester run (README, "Measuring a drape"), measured by
//! [`drape_lab::measure`]; and the same measurement drawn over a top view
//! (`drape render --view top`) and plotted frame by frame (`drape plot`).

use drape::measure::{Given, MeasureError};
use drape_lab::measure::{Report, Run};
use drape_render::{Circle, ExtraPanel, FrameSelect};
use std::path::{Path, PathBuf};

/// What to measure: the run, its frame, the radii given.
pub struct MeasureArgs {
    /// The output directory.
    pub dir: PathBuf,
    /// Which frame.
    pub frame: FrameSelect,
    /// Radii given instead of found.
    pub given: Given,
}

/// `drape measure`: one JSON object on standard output.
///
/// # Errors
/// Every error is the input's (exit status 2): no outputs in the
/// directory, a step that was not written, no instrument to be found.
pub fn run(a: &MeasureArgs) -> anyhow::Result<()> {
    let run = Run::open(&a.dir, a.given)?;
    let index = run.out.select(a.frame)?;
    let m = run.measure(index)?;
    println!("{}", serde_json::to_string(&Report::of(&m))?);
    Ok(())
}

/// The drape tester drawn over a top view of frame `select` of `dir`: the
/// pedestal's rim (solid) and the specimen's circle about its axis
/// (dashed), with the measurement as a caption — a laboratory's picture of
/// the shadow. `None` for a run that is not a drape tester.
pub fn top_view_overlay(dir: &Path, select: FrameSelect) -> Option<(Vec<Circle>, String)> {
    let run = Run::open(dir, Given::default()).ok()?;
    let m = run.measure(run.out.select(select).ok()?).ok()?;
    let t = &m.tester;
    let circle = |radius: f64, color: [u8; 3], dashed: bool| Circle {
        center: t.plane.origin(),
        normal: t.plane.vertical(),
        radius,
        color,
        dashed,
    };
    let caption = format!(
        "drape coefficient {:.3}, {} folds",
        m.measurement.drape_coefficient, m.measurement.folds
    );
    Some((
        vec![
            circle(t.pedestal_radius, [20, 20, 20], false),
            circle(t.specimen_radius, [90, 90, 90], true),
        ],
        caption,
    ))
}

/// The drape coefficient and the folds of every frame of a drape-tester
/// run `dir`, as two plot panels; `None` for a run that is not a drape
/// tester (no pedestal or no disc specimen in its scenario) or whose
/// outputs cannot be read (the plot says what is wrong with them). A
/// drape tester whose first frame cannot be measured has no panels, and
/// a note says why; a later frame that cannot be measured is left out,
/// with a note.
pub fn drape_panels(dir: &Path) -> Option<Vec<ExtraPanel>> {
    let run = Run::open(dir, Given::default()).ok()?;
    if let Err(e) = run.measure(0) {
        let not_a_tester = matches!(
            e.downcast_ref::<MeasureError>(),
            Some(MeasureError::NoPedestal { .. } | MeasureError::NotADisc { .. })
        );
        if !not_a_tester {
            eprintln!("note: no drape coefficient or folds panels: {e:#}");
        }
        return None;
    }
    let (mut time, mut dc, mut folds) = (Vec::new(), Vec::new(), Vec::new());
    for i in 0..run.out.frames.len() {
        match run.measure(i) {
            Ok(m) => {
                time.push(m.entry.time);
                dc.push(m.measurement.drape_coefficient);
                folds.push(m.measurement.folds as f64);
            }
            Err(e) => eprintln!("note: left out of the drape coefficient: {e:#}"),
        }
    }
    Some(vec![
        ExtraPanel {
            title: "Drape coefficient (ISO 9073-9)".into(),
            y_label: "DC".into(),
            time: time.clone(),
            series: vec![("drape coefficient".into(), dc)],
            integer: false,
        },
        ExtraPanel {
            title: "Folds round the rim".into(),
            y_label: "folds".into(),
            time,
            series: vec![("folds".into(), folds)],
            integer: true,
        },
    ])
}
