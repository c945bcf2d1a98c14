//! Animated GIF output (`gif` crate; each frame quantised to its own
//! 256-colour palette by NeuQuant).

use std::io::BufWriter;
use std::path::Path;

use crate::error::{RenderError, Result};
use crate::image::RgbImage;

/// NeuQuant sampling factor: 1 is best and slowest, 30 fastest; 10 is the
/// gif crate's default and gives smooth colour-bar gradients.
const QUANTIZER_SPEED: i32 = 10;

/// How long the last frame is held in addition to the frame delay, ms.
pub(crate) const LAST_FRAME_HOLD_MS: u32 = 1500;

/// Writes `count` frames made by `frame(k)` to the GIF `path`, looping
/// forever.
pub(crate) fn write_gif(
    path: &Path,
    width: u32,
    height: u32,
    delay_ms: u32,
    count: usize,
    mut frame: impl FnMut(usize) -> RgbImage,
) -> Result<()> {
    let (w, h) = (
        u16::try_from(width).map_err(|_| too_large(path))?,
        u16::try_from(height).map_err(|_| too_large(path))?,
    );
    let file = std::fs::File::create(path).map_err(|e| RenderError::io(path, e))?;
    let enc_err = |e: gif::EncodingError| match e {
        gif::EncodingError::Io(io) => RenderError::io(path, io),
        other => RenderError::Encode {
            path: path.to_owned(),
            message: other.to_string(),
        },
    };
    let mut enc = gif::Encoder::new(BufWriter::new(file), w, h, &[]).map_err(enc_err)?;
    enc.set_repeat(gif::Repeat::Infinite).map_err(enc_err)?;
    for k in 0..count {
        let img = frame(k);
        let mut f = gif::Frame::from_rgb_speed(w, h, &img.data, QUANTIZER_SPEED);
        let ms = if k + 1 == count {
            delay_ms.saturating_add(LAST_FRAME_HOLD_MS)
        } else {
            delay_ms
        };
        f.delay = u16::try_from(ms.div_ceil(10)).unwrap_or(u16::MAX);
        enc.write_frame(&f).map_err(enc_err)?;
    }
    enc.into_inner().map_err(enc_err)?;
    Ok(())
}

fn too_large(path: &Path) -> RenderError {
    RenderError::Encode {
        path: path.to_owned(),
        message: "a GIF is at most 65535 pixels wide and high".to_owned(),
    }
}

/// Number of frames of the GIF at `path`, and its size.
///
/// # Errors
/// [`RenderError::Io`] if it cannot be read, [`RenderError::Format`] if it
/// is not a GIF.
pub fn gif_info(path: &Path) -> Result<(usize, u32, u32)> {
    let file = std::fs::File::open(path).map_err(|e| RenderError::io(path, e))?;
    let mut opts = gif::DecodeOptions::new();
    opts.set_color_output(gif::ColorOutput::Indexed);
    let mut dec = opts
        .read_info(std::io::BufReader::new(file))
        .map_err(|e| RenderError::format(path, e.to_string()))?;
    let (w, h) = (dec.width() as u32, dec.height() as u32);
    let mut n = 0;
    while dec
        .read_next_frame()
        .map_err(|e| RenderError::format(path, e.to_string()))?
        .is_some()
    {
        n += 1;
    }
    Ok((n, w, h))
}
