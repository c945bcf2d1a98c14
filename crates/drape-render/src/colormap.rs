//! Colour maps: viridis (perceptually uniform, from matplotlib, through the
//! `colorous` crate) for continuous fields, three fixed colours (Okabe–Ito,
//! colour-blind safe) for the wrinkle state.

/// Colours of the wrinkle states taut, wrinkled, slack (Okabe–Ito blue,
/// orange, reddish purple), as RGB bytes.
pub const WRINKLE_COLOURS: [[u8; 3]; 3] = [[0, 114, 178], [230, 159, 0], [204, 121, 167]];

/// Colour of values that are not finite.
const NAN_COLOUR: [f32; 3] = [0.85, 0.85, 0.85];

/// Maps a scalar to a colour.
#[derive(Debug, Clone)]
pub(crate) enum ColorMap {
    /// Viridis from `min` (dark blue) to `max` (yellow), clamped.
    Continuous {
        lut: Vec<[f32; 3]>,
        min: f64,
        max: f64,
    },
    /// Value `k` (rounded) gets colour `k`.
    Categorical(Vec<[f32; 3]>),
}

fn unit(c: [u8; 3]) -> [f32; 3] {
    c.map(|v| v as f32 / 255.0)
}

impl ColorMap {
    const LUT: usize = 1024;

    /// Viridis over `[min, max]`.
    pub fn viridis(min: f64, max: f64) -> Self {
        let lut = (0..Self::LUT)
            .map(|i| {
                let c = colorous::VIRIDIS.eval_rational(i, Self::LUT);
                unit([c.r, c.g, c.b])
            })
            .collect();
        ColorMap::Continuous { lut, min, max }
    }

    /// The wrinkle-state colours.
    pub fn wrinkle() -> Self {
        ColorMap::Categorical(WRINKLE_COLOURS.iter().map(|&c| unit(c)).collect())
    }

    /// Colour of `v`, channels in [0, 1].
    pub fn color(&self, v: f64) -> [f32; 3] {
        if !v.is_finite() {
            return NAN_COLOUR;
        }
        match self {
            ColorMap::Continuous { lut, min, max } => {
                let t = if max > min {
                    (v - min) / (max - min)
                } else {
                    0.5
                };
                let i = (t.clamp(0.0, 1.0) * (lut.len() - 1) as f64).round() as usize;
                lut[i]
            }
            ColorMap::Categorical(c) => {
                let k = v.round();
                if k >= 0.0 && (k as usize) < c.len() {
                    c[k as usize]
                } else {
                    NAN_COLOUR
                }
            }
        }
    }

    /// Colour at fraction `t` of the range, as bytes (for the colour bar).
    pub fn color_at_fraction(&self, t: f64) -> [u8; 3] {
        let c = match self {
            ColorMap::Continuous { lut, .. } => {
                lut[(t.clamp(0.0, 1.0) * (lut.len() - 1) as f64).round() as usize]
            }
            ColorMap::Categorical(c) => c[((t * c.len() as f64) as usize).min(c.len() - 1)],
        };
        c.map(|v| (v * 255.0).round() as u8)
    }
}

/// The viridis colour at fraction `t` in [0, 1] of the colour bar, as RGB
/// bytes (what the renderer paints for a value at that fraction of the
/// range, before shading).
pub fn viridis(t: f64) -> [u8; 3] {
    let c = colorous::VIRIDIS.eval_rational(
        (t.clamp(0.0, 1.0) * (ColorMap::LUT - 1) as f64).round() as usize,
        ColorMap::LUT,
    );
    [c.r, c.g, c.b]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ends_are_viridis_ends() {
        assert_eq!(viridis(0.0), [0x44, 0x01, 0x54]);
        assert_eq!(viridis(1.0), [0xfd, 0xe7, 0x25]);
        let m = ColorMap::viridis(-1.0, 1.0);
        assert_eq!(m.color_at_fraction(0.0), viridis(0.0));
        assert_eq!(m.color(5.0), m.color(1.0));
    }
}
