//! Obstacles from a scenario file: only its `[[obstacle]]` tables are read,
//! with the keys of the README's `[[obstacle]]` section; everything else in
//! the file is ignored (`drape check` validates scenarios, not this).

use std::path::Path;

use serde::Deserialize;

use crate::error::{RenderError, Result};

type V3 = [f64; 3];

/// A rigid obstacle's shape, at t = 0.
#[derive(Debug, Clone, PartialEq)]
pub enum Shape {
    /// A plane through `point` with outward `normal` (not normalised).
    Plane {
        /// A point on the plane.
        point: V3,
        /// Its normal.
        normal: V3,
    },
    /// An axis-aligned box.
    Box {
        /// Lower corner.
        min: V3,
        /// Upper corner.
        max: V3,
    },
    /// A sphere.
    Sphere {
        /// Centre.
        center: V3,
        /// Radius.
        radius: f64,
    },
    /// A capped cylinder.
    Cylinder {
        /// Centre of the top face.
        center: V3,
        /// Direction from the bottom to the top face (not normalised).
        axis: V3,
        /// Radius.
        radius: f64,
        /// Height.
        height: f64,
    },
}

/// An obstacle: its shape at t = 0 and its rigid velocity.
#[derive(Debug, Clone, PartialEq)]
pub struct Obstacle {
    /// Shape at t = 0.
    pub shape: Shape,
    /// Translation velocity (m/s): at time t the obstacle has moved by
    /// `velocity * t`.
    pub velocity: V3,
}

#[derive(Debug, Deserialize)]
struct File {
    #[serde(default)]
    obstacle: Vec<Raw>,
}

#[derive(Debug, Deserialize)]
struct Raw {
    shape: Option<String>,
    point: Option<V3>,
    normal: Option<V3>,
    min: Option<V3>,
    max: Option<V3>,
    center: Option<V3>,
    radius: Option<f64>,
    axis: Option<V3>,
    height: Option<f64>,
    path: Option<String>,
    velocity: Option<V3>,
}

#[derive(Debug, Deserialize)]
struct Monitors {
    #[serde(default)]
    monitor: Vec<NamedMonitor>,
}

#[derive(Debug, Deserialize)]
struct NamedMonitor {
    name: Option<String>,
}

#[derive(Debug, Deserialize)]
struct MaterialOf {
    material: Option<WrinklingOf>,
}

#[derive(Debug, Deserialize)]
struct WrinklingOf {
    wrinkling: Option<TensionField>,
}

/// `[material] wrinkling`, as the library spells it.
#[derive(Debug, Deserialize, PartialEq)]
#[serde(rename_all = "kebab-case")]
enum TensionField {
    None,
    StressProjection,
    RelaxedEnergy,
}

/// Whether a scenario's material has a tension-field model (`[material]
/// wrinkling` other than `"none"`, whose default it is); `None` when the
/// text does not parse.
pub fn has_tension_field(text: &str) -> Option<bool> {
    let m = toml::from_str::<MaterialOf>(text).ok()?;
    let wrinkling = m.material.and_then(|m| m.wrinkling);
    Some(wrinkling.is_some_and(|w| w != TensionField::None))
}

/// The names of the `[[monitor]]` tables of a scenario's text (none when
/// the text does not parse: the renderer reads scenarios leniently).
pub fn monitor_names(text: &str) -> Vec<String> {
    toml::from_str::<Monitors>(text)
        .map(|m| m.monitor.into_iter().filter_map(|m| m.name).collect())
        .unwrap_or_default()
}

/// Reads the obstacles of the scenario file at `path`. Mesh obstacles are
/// not drawn: each gives a notice in the second vector.
///
/// # Errors
/// [`RenderError::Io`] if the file cannot be read,
/// [`RenderError::Scenario`] if it is not TOML or an obstacle lacks a key
/// its shape needs or has a non-finite or non-positive size.
pub fn read_obstacles(path: &Path) -> Result<(Vec<Obstacle>, Vec<String>)> {
    let text = std::fs::read_to_string(path).map_err(|e| RenderError::io(path, e))?;
    parse_obstacles(path, &text)
}

/// As [`read_obstacles`], from the file's text (`path` is for messages).
///
/// # Errors
/// As [`read_obstacles`].
pub fn parse_obstacles(path: &Path, text: &str) -> Result<(Vec<Obstacle>, Vec<String>)> {
    let err = |m: String| RenderError::Scenario {
        path: path.to_owned(),
        message: m,
    };
    let file: File = toml::from_str(text).map_err(|e| err(e.to_string().trim().to_owned()))?;
    let mut out = Vec::new();
    let mut notices = Vec::new();
    for (i, r) in file.obstacle.into_iter().enumerate() {
        // Numbered from 0, as `drape check` and `drape measure` name them.
        let n = format!("obstacle[{i}]");
        let need_v = |v: Option<V3>, key: &str| -> Result<V3> {
            let v = v.ok_or_else(|| err(format!("{n}: missing {key}")))?;
            if v.iter().all(|x| x.is_finite()) {
                Ok(v)
            } else {
                Err(err(format!("{n}: {key} is not finite")))
            }
        };
        let need_pos = |v: Option<f64>, key: &str| -> Result<f64> {
            let v = v.ok_or_else(|| err(format!("{n}: missing {key}")))?;
            if v.is_finite() && v > 0.0 {
                Ok(v)
            } else {
                Err(err(format!("{n}: {key} must be > 0")))
            }
        };
        let shape = match r.shape.as_deref() {
            Some("plane") => {
                let normal = need_v(r.normal, "normal")?;
                if normal.iter().all(|&x| x == 0.0) {
                    return Err(err(format!("{n}: normal is zero")));
                }
                Shape::Plane {
                    point: need_v(r.point, "point")?,
                    normal,
                }
            }
            Some("box") => {
                let min = need_v(r.min, "min")?;
                let max = need_v(r.max, "max")?;
                if (0..3).any(|k| min[k] >= max[k]) {
                    return Err(err(format!("{n}: min must be < max")));
                }
                Shape::Box { min, max }
            }
            Some("sphere") => Shape::Sphere {
                center: need_v(r.center, "center")?,
                radius: need_pos(r.radius, "radius")?,
            },
            Some("cylinder") => {
                let axis = need_v(r.axis, "axis")?;
                if axis.iter().all(|&x| x == 0.0) {
                    return Err(err(format!("{n}: axis is zero")));
                }
                Shape::Cylinder {
                    center: need_v(r.center, "center")?,
                    axis,
                    radius: need_pos(r.radius, "radius")?,
                    height: need_pos(r.height, "height")?,
                }
            }
            Some("mesh") => {
                notices.push(format!(
                    "{n} (mesh {}) is not drawn: mesh obstacles are not rendered",
                    r.path.as_deref().unwrap_or("?")
                ));
                continue;
            }
            Some(other) => return Err(err(format!("{n}: unknown shape {other:?}"))),
            None => return Err(err(format!("{n}: missing shape"))),
        };
        let velocity = match r.velocity {
            Some(v) => need_v(Some(v), "velocity")?,
            None => [0.0; 3],
        };
        out.push(Obstacle { shape, velocity });
    }
    Ok((out, notices))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_shapes_and_ignores_the_rest() {
        let t = r#"
title = "x"
[mesh]
shape = "rectangle"
[[obstacle]]
shape = "box"
min = [-0.05, -0.05, -0.25]
max = [0.05, 0.05, -0.05]
[[obstacle]]
shape = "cylinder"
center = [0, 0, -0.05]
axis = [0, 0, 1]
radius = 0.09
height = 0.2
velocity = [0, 0, 1]
[[obstacle]]
shape = "mesh"
path = "a.obj"
"#;
        let (o, notes) = parse_obstacles(Path::new("s.toml"), t).unwrap();
        assert_eq!(o.len(), 2);
        assert_eq!(notes.len(), 1);
        assert_eq!(o[1].velocity, [0.0, 0.0, 1.0]);
        assert!(parse_obstacles(Path::new("s.toml"), "[[obstacle]]\nshape = \"box\"\n").is_err());
        assert!(parse_obstacles(Path::new("s.toml"), "not toml [").is_err());
    }
}
