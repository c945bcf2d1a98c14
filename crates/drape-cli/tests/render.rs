//! `drape render` and `drape plot` work on the outputs of every example.

use std::path::{Path, PathBuf};
use std::process::Command;

fn drape(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_drape"))
        .args(args)
        .output()
        .unwrap()
}

/// Each example, cut to a few steps of its last segment's size, or to
/// four load increments when static (the rendering, not the mechanics, is
/// under test).
fn short_example(file: &Path, dir: &Path) -> PathBuf {
    let text = std::fs::read_to_string(file).unwrap();
    let mut table = String::new();
    let text: String = text
        .lines()
        .map(|l| {
            if l.trim_start().starts_with('[') {
                table = l.split('#').next().unwrap_or("").trim().to_string();
            }
            if table == "[analysis]" && l.trim_start().starts_with("steps") {
                "steps = 4".to_string()
            } else if l.trim_start().starts_with("segments") {
                let dt = l
                    .rsplit("dt =")
                    .next()
                    .unwrap()
                    .split('}')
                    .next()
                    .unwrap()
                    .trim();
                format!("segments = [{{ steps = 4, dt = {dt} }}]")
            } else if l.trim_start().starts_with("every =") {
                "every = 2".to_string()
            } else {
                l.to_string()
            }
        })
        .collect::<Vec<_>>()
        .join("\n");
    let path = dir.join(file.file_name().unwrap());
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn render_grid_animation_and_plot_work_on_every_example() {
    let dir = std::env::temp_dir().join(format!("drape-render-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let examples = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples");
    // The meshes some examples read, beside their shortened copies.
    let meshes = dir.join("meshes");
    std::fs::create_dir_all(&meshes).unwrap();
    for entry in std::fs::read_dir(examples.join("meshes")).unwrap() {
        let path = entry.unwrap().path();
        std::fs::copy(&path, meshes.join(path.file_name().unwrap())).unwrap();
    }
    let mut files: Vec<PathBuf> = std::fs::read_dir(&examples)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    files.sort();
    for file in files {
        let scenario = short_example(&file, &dir);
        let out = dir.join(file.file_stem().unwrap());
        let o = drape(&[
            "run",
            scenario.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--quiet",
        ]);
        assert!(
            o.status.success(),
            "{}: {}",
            file.display(),
            String::from_utf8_lossy(&o.stderr)
        );
        let out_s = out.to_str().unwrap();
        for args in [
            vec!["render", out_s, "--size", "400x300"],
            vec![
                "render",
                out_s,
                "--view",
                "top",
                "--field",
                "wrinkle_state",
                "-o",
                "top.png",
                "--size",
                "400x300",
            ],
            vec![
                "render", out_s, "--grid", "--panels", "3", "--size", "600x400",
            ],
            vec!["render", out_s, "--animate", "--size", "200x150"],
            vec!["plot", out_s, "--size", "600x450"],
        ] {
            let args: Vec<String> = args
                .iter()
                .map(|a| {
                    if *a == "top.png" {
                        out.join("top.png").to_string_lossy().into_owned()
                    } else {
                        a.to_string()
                    }
                })
                .collect();
            let args: Vec<&str> = args.iter().map(String::as_str).collect();
            let o = drape(&args);
            assert!(
                o.status.success(),
                "{}: drape {args:?}: {}",
                file.display(),
                String::from_utf8_lossy(&o.stderr)
            );
        }
        let png = drape_render::RgbImage::read_png(&out.join("render.png")).unwrap();
        assert_eq!((png.width, png.height), (400, 300));
        let plot = drape_render::RgbImage::read_png(&out.join("plot.png")).unwrap();
        assert_eq!((plot.width, plot.height), (600, 450));
        // One animation frame per written frame: the initial state, then
        // every second step of four (steps 2 and 4; more where a step was
        // cut back into shorter ones, as a static increment may be).
        let written = std::fs::read_to_string(out.join("fields.pvd"))
            .unwrap()
            .matches("<DataSet")
            .count();
        assert!(written >= 3, "{}: {written} frames", file.display());
        let (frames, w, h) = drape_render::gif_info(&out.join("animation.gif")).unwrap();
        assert_eq!((frames, w, h), (written, 200, 150), "{}", file.display());
    }
    let _ = std::fs::remove_dir_all(&dir);
}
