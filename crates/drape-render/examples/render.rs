//! Minimal driver until the `drape render` / `drape plot` verbs are wired:
//!
//! ```text
//! cargo run --release -p drape-render --example render -- DIR [render|grid|animate|plot]
//!     [--view V] [--field F] [--step N] [--time T] [--scenario FILE] [--size WxH] [-o FILE]
//! ```
use std::path::PathBuf;

use drape_render::{FrameSelect, Layout, RenderOptions, plot, render};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let dir = PathBuf::from(
        args.next()
            .ok_or("usage: DIR [render|grid|animate|plot] ...")?,
    );
    let mut mode = "render".to_owned();
    let mut opts = RenderOptions::default();
    while let Some(a) = args.next() {
        let mut val = || args.next().ok_or(format!("{a} needs a value"));
        match a.as_str() {
            "render" | "grid" | "animate" | "plot" => mode = a.clone(),
            "--view" => opts.view = val()?.parse()?,
            "--field" => opts.field = val()?.parse()?,
            "--step" => opts.frame = FrameSelect::Step(val()?.parse()?),
            "--time" => opts.frame = FrameSelect::Time(val()?.parse()?),
            "--scenario" => opts.scenario = Some(val()?.into()),
            "--edges" => opts.edges = Some(val()? == "on"),
            "--size" => {
                let v = val()?;
                let (w, h) = v.split_once('x').ok_or("--size WxH")?;
                opts.width = w.parse()?;
                opts.height = h.parse()?;
            }
            "-o" => opts.output = Some(val()?.into()),
            other => return Err(format!("unknown argument {other}").into()),
        }
    }
    if mode == "plot" {
        let out = opts.output.unwrap_or_else(|| dir.join("plot.png"));
        let r = plot(&dir, &out, opts.width, opts.height)?;
        println!("{}: {} rows, panels {:?}", out.display(), r.rows, r.panels);
        return Ok(());
    }
    opts.layout = match mode.as_str() {
        "grid" => Layout::Grid { panels: 6 },
        "animate" => Layout::Animation {
            frame_delay_ms: 100,
        },
        _ => Layout::Single,
    };
    let t = std::time::Instant::now();
    let r = render(&dir, &opts)?;
    println!(
        "{}: {} frame(s), {} = [{}, {}], labels {:?}, {} obstacle(s), {:.2} s",
        r.output
            .as_ref()
            .map(|p| p.display().to_string())
            .unwrap_or_default(),
        r.frames.len(),
        r.caption,
        r.range.0,
        r.range.1,
        r.colorbar_labels,
        r.obstacles,
        t.elapsed().as_secs_f64()
    );
    for n in &r.notices {
        println!("note: {n}");
    }
    Ok(())
}
