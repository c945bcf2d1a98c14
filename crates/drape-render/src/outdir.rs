//! An output directory of `drape run`: the frame list of `fields.pvd`, the
//! title from `summary.json` and the columns of `history.csv`.

use std::path::{Path, PathBuf};

use crate::error::{RenderError, Result};

/// One frame listed in `fields.pvd`.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameEntry {
    /// Simulated time (s), from the collection's `timestep`.
    pub time: f64,
    /// Step number, from the file name `step_NNNNNN.vtu` (the frame's index
    /// in the collection if the name has none).
    pub step: u64,
    /// The `.vtu` file.
    pub path: PathBuf,
}

/// Checks that `path` is a directory: one that does not exist, or a file,
/// is an [`RenderError::Io`] saying which, as a drape output directory was
/// expected.
pub(crate) fn require_dir(path: &Path) -> Result<()> {
    use std::io::ErrorKind;
    let (kind, what) = match std::fs::metadata(path) {
        Ok(m) if m.is_dir() => return Ok(()),
        Ok(_) => (ErrorKind::NotADirectory, "not a directory"),
        Err(e) if e.kind() == ErrorKind::NotFound => (ErrorKind::NotFound, "does not exist"),
        Err(e) => return Err(RenderError::io(path, e)),
    };
    Err(RenderError::io(
        path,
        std::io::Error::new(kind, format!("{what} (expected a drape output directory)")),
    ))
}

/// Which frame to render.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum FrameSelect {
    /// The last frame written.
    #[default]
    Last,
    /// The frame of this step (it must have been written).
    Step(u64),
    /// The frame nearest this time (s).
    Time(f64),
}

/// A drape output directory, opened.
#[derive(Debug, Clone)]
pub struct OutputDir {
    /// The directory.
    pub dir: PathBuf,
    /// Frames of `fields.pvd`, in file order.
    pub frames: Vec<FrameEntry>,
    /// `title` of `summary.json`, else the directory's name.
    pub title: String,
}

impl OutputDir {
    /// Opens `path`: an output directory, or its `fields.pvd`.
    ///
    /// # Errors
    /// [`RenderError::Io`] if `fields.pvd` cannot be read,
    /// [`RenderError::Format`] if it is not a collection file,
    /// [`RenderError::NoFrames`] if it lists no frame.
    pub fn open(path: &Path) -> Result<Self> {
        let (dir, pvd) = if path.extension().is_some_and(|e| e == "pvd") {
            (
                path.parent().unwrap_or(Path::new(".")).to_owned(),
                path.to_owned(),
            )
        } else {
            require_dir(path)?;
            (path.to_owned(), path.join("fields.pvd"))
        };
        let text = std::fs::read_to_string(&pvd).map_err(|e| RenderError::io(&pvd, e))?;
        let frames = parse_pvd(&pvd, &dir, &text)?;
        if frames.is_empty() {
            return Err(RenderError::NoFrames { path: pvd });
        }
        let title = read_title(&dir).unwrap_or_else(|| {
            dir.file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_else(|| "drape".to_owned())
        });
        Ok(Self { dir, frames, title })
    }

    /// Index into [`OutputDir::frames`] of the selected frame.
    ///
    /// # Errors
    /// [`RenderError::StepNotFound`] for a step that was not written,
    /// [`RenderError::InvalidOption`] for a time that is not finite.
    pub fn select(&self, sel: FrameSelect) -> Result<usize> {
        match sel {
            FrameSelect::Last => Ok(self.frames.len() - 1),
            FrameSelect::Step(s) => self.frames.iter().position(|f| f.step == s).ok_or_else(|| {
                RenderError::StepNotFound {
                    path: self.dir.join("fields.pvd"),
                    step: s,
                    available: summarize_steps(&self.frames),
                }
            }),
            FrameSelect::Time(t) => {
                if !t.is_finite() {
                    return Err(RenderError::InvalidOption(format!(
                        "--time {t}: not a finite time"
                    )));
                }
                if t < 0.0 {
                    let (first, last) =
                        (self.frames[0].time, self.frames[self.frames.len() - 1].time);
                    return Err(RenderError::InvalidOption(format!(
                        "--time {t}: a run's time is not negative; its frames span t = {first} to {last} s"
                    )));
                }
                // Past the last frame (or before the first) the nearest is
                // the end itself: at a time so large that every distance
                // rounds to the same value, the loop below would keep the
                // first frame.
                let last = self.frames.len() - 1;
                if t >= self.frames[last].time {
                    return Ok(last);
                }
                if t <= self.frames[0].time {
                    return Ok(0);
                }
                let mut best = 0;
                for (i, f) in self.frames.iter().enumerate() {
                    if (f.time - t).abs() < (self.frames[best].time - t).abs() {
                        best = i;
                    }
                }
                Ok(best)
            }
        }
    }

    /// About `count` frame indices spread evenly over the frames written (by
    /// index, so by steps: where the solver spent its steps, which is where
    /// things happen), always the first and the last, without repeats.
    pub fn spread(&self, count: usize) -> Vec<usize> {
        let n = self.frames.len();
        let count = count.clamp(1, n);
        if count == 1 {
            return vec![n - 1];
        }
        let mut out: Vec<usize> = (0..count)
            .map(|k| ((k as f64) * (n - 1) as f64 / (count - 1) as f64).round() as usize)
            .collect();
        out.dedup();
        out
    }
}

fn summarize_steps(frames: &[FrameEntry]) -> String {
    let steps: Vec<String> = frames.iter().map(|f| f.step.to_string()).collect();
    if steps.len() <= 12 {
        steps.join(", ")
    } else {
        format!(
            "{}, …, {} ({} frames)",
            steps[..6].join(", "),
            steps[steps.len() - 3..].join(", "),
            steps.len()
        )
    }
}

fn read_title(dir: &Path) -> Option<String> {
    let text = std::fs::read_to_string(dir.join("summary.json")).ok()?;
    let v: serde_json::Value = serde_json::from_str(&text).ok()?;
    v.get("title")?
        .as_str()
        .map(str::to_owned)
        .filter(|s| !s.is_empty())
}

/// Parses the `<DataSet timestep=".." file=".."/>` entries of a collection.
fn parse_pvd(pvd: &Path, dir: &Path, text: &str) -> Result<Vec<FrameEntry>> {
    if !text.contains("<VTKFile") || !text.contains("Collection") {
        return Err(RenderError::format(
            pvd,
            "not a ParaView collection file (no <VTKFile type=\"Collection\">)",
        ));
    }
    let mut out = Vec::new();
    let mut rest = text;
    while let Some(at) = rest.find("<DataSet") {
        let tail = &rest[at + "<DataSet".len()..];
        let end = tail
            .find('>')
            .ok_or_else(|| RenderError::format(pvd, "unterminated <DataSet> tag"))?;
        let attrs = &tail[..end];
        let get = |key: &str| -> Option<String> {
            let pat = format!("{key}=\"");
            let s = attrs.find(&pat)? + pat.len();
            let e = attrs[s..].find('"')? + s;
            Some(attrs[s..e].to_owned())
        };
        let index = out.len();
        let time: f64 = get("timestep")
            .and_then(|t| t.trim().parse().ok())
            .filter(|t: &f64| t.is_finite())
            .ok_or_else(|| {
                RenderError::format(pvd, format!("DataSet {index}: no valid timestep"))
            })?;
        let file = get("file")
            .filter(|f| !f.is_empty())
            .ok_or_else(|| RenderError::format(pvd, format!("DataSet {index}: no file")))?;
        let step = step_of(&file).unwrap_or(index as u64);
        out.push(FrameEntry {
            time,
            step,
            path: dir.join(&file),
        });
        rest = &tail[end..];
    }
    Ok(out)
}

/// The step number of `.../step_000123.vtu`.
fn step_of(file: &str) -> Option<u64> {
    let name = file.rsplit('/').next()?;
    let digits = name.strip_prefix("step_")?.strip_suffix(".vtu")?;
    digits.parse().ok()
}

/// The columns of `history.csv`, by name.
#[derive(Debug, Clone)]
pub struct History {
    /// Column names, in file order.
    pub names: Vec<String>,
    /// Column values, one vector per name, one entry per row.
    pub columns: Vec<Vec<f64>>,
}

impl History {
    /// Reads `dir/history.csv`.
    ///
    /// A last line without its newline that does not parse (a run killed in
    /// the middle of writing) is left out.
    ///
    /// # Errors
    /// [`RenderError::Io`] if it cannot be read, [`RenderError::Format`] if
    /// it has no header or a row of the wrong length or a non-number
    /// (naming the line).
    pub fn read(dir: &Path) -> Result<Self> {
        let path = dir.join("history.csv");
        let text = std::fs::read_to_string(&path).map_err(|e| RenderError::io(&path, e))?;
        let mut lines = text.split('\n').enumerate().peekable();
        let (_, header) = lines
            .next()
            .filter(|(_, h)| !h.trim().is_empty())
            .ok_or_else(|| RenderError::format(&path, "empty file: no header"))?;
        let names: Vec<String> = header
            .trim()
            .split(',')
            .map(|s| s.trim().to_owned())
            .collect();
        let mut columns = vec![Vec::new(); names.len()];
        while let Some((i, line)) = lines.next() {
            let line = line.trim();
            if line.is_empty() {
                continue;
            }
            let last_unterminated = lines.peek().is_none();
            let values: Option<Vec<f64>> =
                line.split(',').map(|s| parse_number(s.trim())).collect();
            match values {
                Some(v) if v.len() == names.len() => {
                    for (c, x) in columns.iter_mut().zip(v) {
                        c.push(x);
                    }
                }
                _ if last_unterminated => break,
                Some(v) => {
                    return Err(RenderError::format(
                        &path,
                        format!(
                            "line {}: {} values, the header has {} columns",
                            i + 1,
                            v.len(),
                            names.len()
                        ),
                    ));
                }
                None => {
                    return Err(RenderError::format(
                        &path,
                        format!("line {}: a value is not a number", i + 1),
                    ));
                }
            }
        }
        Ok(Self { names, columns })
    }

    /// The column named `name`.
    pub fn column(&self, name: &str) -> Option<&[f64]> {
        self.names
            .iter()
            .position(|n| n == name)
            .map(|i| self.columns[i].as_slice())
    }

    /// Number of rows.
    pub fn rows(&self) -> usize {
        self.columns.first().map_or(0, Vec::len)
    }

    /// Names of the monitors: every `<name>` with columns `<name>_x`,
    /// `<name>_y`, `<name>_z` in a row.
    pub fn monitors(&self) -> Vec<String> {
        let mut out = Vec::new();
        for w in self.names.windows(3) {
            if let Some(base) = w[0].strip_suffix("_x")
                && w[1].strip_suffix("_y") == Some(base)
                && w[2].strip_suffix("_z") == Some(base)
            {
                out.push(base.to_owned());
            }
        }
        out
    }
}

fn parse_number(s: &str) -> Option<f64> {
    match s {
        "NaN" | "nan" => Some(f64::NAN),
        "inf" | "Infinity" => Some(f64::INFINITY),
        "-inf" | "-Infinity" => Some(f64::NEG_INFINITY),
        _ => s.parse().ok(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn steps() {
        assert_eq!(step_of("fields/step_000460.vtu"), Some(460));
        assert_eq!(step_of("fields/other.vtu"), None);
    }

    #[test]
    fn pvd() {
        let t = r#"<?xml version="1.0"?>
<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">
  <Collection>
    <DataSet timestep="0" group="" part="0" file="fields/step_000000.vtu"/>
    <DataSet timestep="0.5" group="" part="0" file="fields/step_000010.vtu"/>
  </Collection>
</VTKFile>"#;
        let f = parse_pvd(Path::new("a.pvd"), Path::new("d"), t).unwrap();
        assert_eq!(f.len(), 2);
        assert_eq!(f[1].step, 10);
        assert_eq!(f[1].time, 0.5);
        assert_eq!(f[1].path, Path::new("d/fields/step_000010.vtu"));
        assert!(parse_pvd(Path::new("a.pvd"), Path::new("d"), "hello").is_err());
    }

    #[test]
    fn spread_and_select() {
        let frames: Vec<FrameEntry> = (0..48)
            .map(|i| FrameEntry {
                time: i as f64 * 0.01,
                step: i * 10,
                path: PathBuf::new(),
            })
            .collect();
        let o = OutputDir {
            dir: PathBuf::new(),
            frames,
            title: String::new(),
        };
        let s = o.spread(6);
        assert_eq!(s.first(), Some(&0));
        assert_eq!(s.last(), Some(&47));
        assert_eq!(s.len(), 6);
        assert_eq!(o.spread(100).len(), 48);
        assert_eq!(o.select(FrameSelect::Step(20)).unwrap(), 2);
        assert!(o.select(FrameSelect::Step(21)).is_err());
        assert_eq!(o.select(FrameSelect::Time(0.104)).unwrap(), 10);
        // Far past the end, the last frame (issue 35: step 0 was taken,
        // every distance rounding to 1e17).
        let last = o.frames.len() - 1;
        assert_eq!(o.select(FrameSelect::Time(1e17)).unwrap(), last);
        assert_eq!(o.select(FrameSelect::Last).unwrap(), 47);
    }
}
