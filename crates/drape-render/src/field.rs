//! The scalar fields a render can colour the fabric by.

use std::fmt;
use std::str::FromStr;

use crate::error::{RenderError, Result};
use crate::vtu::Frame;

/// A scalar field of a frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Field {
    /// Vertical (z) displacement, m (point data).
    #[default]
    DisplacementZ,
    /// Magnitude of the displacement, m (point data).
    Displacement,
    /// Magnitude of the velocity, m/s (point data).
    Velocity,
    /// Magnitude of the nodal contact force, N (point data).
    ContactForce,
    /// Larger principal stress (second Piola–Kirchhoff), Pa (cell data).
    PrincipalStressMax,
    /// Smaller principal stress, Pa (cell data).
    PrincipalStressMin,
    /// Wrinkling state per element: 0 taut, 1 wrinkled, 2 slack (cell data,
    /// categorical).
    WrinkleState,
}

/// Where a field's values live.
#[derive(Debug, Clone, PartialEq)]
pub enum FieldValues {
    /// One value per point (interpolated over each triangle).
    Point(Vec<f64>),
    /// One value per cell (constant over each element).
    Cell(Vec<f64>),
}

impl FieldValues {
    /// The values.
    pub fn values(&self) -> &[f64] {
        match self {
            FieldValues::Point(v) | FieldValues::Cell(v) => v,
        }
    }

    /// Smallest and largest finite value, if any.
    pub fn range(&self) -> Option<(f64, f64)> {
        finite_range(self.values())
    }
}

/// Smallest and largest finite value of `v`, if any.
pub fn finite_range(v: &[f64]) -> Option<(f64, f64)> {
    v.iter().filter(|x| x.is_finite()).fold(None, |acc, &x| {
        Some(match acc {
            None => (x, x),
            Some((a, b)) => (a.min(x), b.max(x)),
        })
    })
}

/// The categories of [`Field::WrinkleState`], by value.
pub const WRINKLE_STATES: [&str; 3] = ["taut", "wrinkled", "slack"];

impl Field {
    /// Every field, in the order of the help text.
    pub const ALL: [Field; 7] = [
        Field::DisplacementZ,
        Field::Displacement,
        Field::Velocity,
        Field::ContactForce,
        Field::PrincipalStressMax,
        Field::PrincipalStressMin,
        Field::WrinkleState,
    ];

    /// The name used on the command line and on the colour bar.
    pub fn name(self) -> &'static str {
        match self {
            Field::DisplacementZ => "displacement_z",
            Field::Displacement => "displacement",
            Field::Velocity => "velocity",
            Field::ContactForce => "contact_force",
            Field::PrincipalStressMax => "principal_stress_max",
            Field::PrincipalStressMin => "principal_stress_min",
            Field::WrinkleState => "wrinkle_state",
        }
    }

    /// The SI unit (empty for the categorical wrinkle state).
    pub fn unit(self) -> &'static str {
        match self {
            Field::DisplacementZ | Field::Displacement => "m",
            Field::Velocity => "m/s",
            Field::ContactForce => "N",
            Field::PrincipalStressMax | Field::PrincipalStressMin => "Pa",
            Field::WrinkleState => "",
        }
    }

    /// A short description, for help texts.
    pub fn description(self) -> &'static str {
        match self {
            Field::DisplacementZ => "vertical displacement (m)",
            Field::Displacement => "displacement magnitude (m)",
            Field::Velocity => "speed (m/s)",
            Field::ContactForce => "nodal contact force magnitude (N)",
            Field::PrincipalStressMax => "larger principal stress S1 (Pa), per element",
            Field::PrincipalStressMin => "smaller principal stress S2 (Pa), per element",
            Field::WrinkleState => "taut / wrinkled / slack, per element",
        }
    }

    /// The colour bar's caption: name and unit, `displacement_z (m)`.
    pub fn label(self) -> String {
        match self.unit() {
            "" => self.name().to_owned(),
            u => format!("{} ({u})", self.name()),
        }
    }

    /// Whether the field is categorical (a legend instead of a colour bar).
    pub fn is_categorical(self) -> bool {
        self == Field::WrinkleState
    }

    /// The field's values on `frame`.
    ///
    /// # Errors
    /// [`RenderError::MissingArray`] if the frame lacks the array, or has it
    /// with too few components.
    pub fn extract(self, frame: &Frame) -> Result<FieldValues> {
        let missing = |kind, array: &str| RenderError::MissingArray {
            path: frame.path.clone(),
            kind,
            array: array.to_owned(),
            field: self.name().to_owned(),
        };
        let point = |name: &str, min_comp: usize| {
            frame
                .point_array(name)
                .filter(|a| a.components >= min_comp)
                .ok_or_else(|| missing("point", name))
        };
        let cell = |name: &str, min_comp: usize| {
            frame
                .cell_array(name)
                .filter(|a| a.components >= min_comp)
                .ok_or_else(|| missing("cell", name))
        };
        let magnitude = |name: &str| -> Result<FieldValues> {
            let a = point(name, 3)?;
            Ok(FieldValues::Point(
                a.values
                    .chunks_exact(a.components)
                    .map(|c| (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt())
                    .collect(),
            ))
        };
        let component = |a: &crate::vtu::Array, k: usize| -> Vec<f64> {
            a.values.chunks_exact(a.components).map(|c| c[k]).collect()
        };
        Ok(match self {
            Field::DisplacementZ => FieldValues::Point(component(point("displacement", 3)?, 2)),
            Field::Displacement => magnitude("displacement")?,
            Field::Velocity => magnitude("velocity")?,
            Field::ContactForce => magnitude("contact_force")?,
            Field::PrincipalStressMax => {
                FieldValues::Cell(component(cell("principal_stress", 2)?, 0))
            }
            Field::PrincipalStressMin => {
                FieldValues::Cell(component(cell("principal_stress", 2)?, 1))
            }
            Field::WrinkleState => FieldValues::Cell(component(cell("wrinkle_state", 1)?, 0)),
        })
    }
}

impl fmt::Display for Field {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Field {
    type Err = RenderError;

    fn from_str(s: &str) -> Result<Self> {
        Field::ALL
            .into_iter()
            .find(|f| f.name() == s)
            .ok_or_else(|| {
                let names: Vec<&str> = Field::ALL.iter().map(|f| f.name()).collect();
                RenderError::InvalidOption(format!(
                    "unknown field {s:?}; the fields are {}",
                    names.join(", ")
                ))
            })
    }
}

// The command line's `--field`, by [`Field::name`].
#[cfg(feature = "clap")]
crate::value_enum_by_name!(Field);

/// Formats a colour-bar or axis value with 4 significant digits, plain or
/// in scientific notation (`-0.05`, `0.1523`, `1234`, `1.5e-7`), with an
/// ASCII minus.
pub fn format_value(v: f64) -> String {
    if v == 0.0 {
        return "0".to_owned();
    }
    if !v.is_finite() {
        return format!("{v}");
    }
    let a = v.abs();
    if (1e-3..1e5).contains(&a) {
        let digits = (3 - a.log10().floor() as i32).max(0) as usize;
        let s = format!("{v:.digits$}");
        trim_zeros(&s)
    } else {
        let s = format!("{v:.3e}");
        let (m, e) = s.split_once('e').unwrap_or((&s, "0"));
        format!("{}e{e}", trim_zeros(m))
    }
}

fn trim_zeros(s: &str) -> String {
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_owned()
    } else {
        s.to_owned()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn formats() {
        assert_eq!(format_value(0.0), "0");
        assert_eq!(format_value(-0.05), "-0.05");
        assert_eq!(format_value(0.15234), "0.1523");
        assert_eq!(format_value(1234.0), "1234");
        assert_eq!(format_value(12345.6), "12346");
        assert_eq!(format_value(1.5e-7), "1.5e-7");
        assert_eq!(format_value(-2.0e6), "-2e6");
        assert_eq!(format_value(0.001), "0.001");
    }

    #[test]
    fn names_round_trip() {
        for f in Field::ALL {
            assert_eq!(f.name().parse::<Field>().unwrap(), f);
        }
        assert!("nope".parse::<Field>().is_err());
    }
}
