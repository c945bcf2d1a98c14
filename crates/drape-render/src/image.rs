//! A plain RGB image with PNG input and output (`png` crate).

use std::io::BufWriter;
use std::path::Path;

use crate::error::{RenderError, Result};

/// An 8-bit RGB image, rows top to bottom.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RgbImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width * height` pixels of 3 bytes.
    pub data: Vec<u8>,
}

impl RgbImage {
    /// A white image.
    pub fn new(width: u32, height: u32) -> Self {
        Self {
            width,
            height,
            data: vec![255; width as usize * height as usize * 3],
        }
    }

    /// The pixel at `(x, y)`; `None` outside.
    pub fn get(&self, x: u32, y: u32) -> Option<[u8; 3]> {
        if x >= self.width || y >= self.height {
            return None;
        }
        let i = 3 * (y as usize * self.width as usize + x as usize);
        Some([self.data[i], self.data[i + 1], self.data[i + 2]])
    }

    /// Sets the pixel at `(x, y)` (ignored outside).
    pub fn put(&mut self, x: usize, y: usize, c: [u8; 3]) {
        if x < self.width as usize && y < self.height as usize {
            let i = 3 * (y * self.width as usize + x);
            self.data[i..i + 3].copy_from_slice(&c);
        }
    }

    /// Blends `c` over the pixel at `(x, y)` with coverage `a` in [0, 1].
    pub fn blend(&mut self, x: i64, y: i64, c: [u8; 3], a: f32) {
        if x < 0 || y < 0 || x >= self.width as i64 || y >= self.height as i64 {
            return;
        }
        let a = a.clamp(0.0, 1.0);
        let i = 3 * (y as usize * self.width as usize + x as usize);
        for (k, &ck) in c.iter().enumerate() {
            let d = self.data[i + k] as f32;
            self.data[i + k] = (d + (ck as f32 - d) * a).round() as u8;
        }
    }

    /// Fills the rectangle `[x0, x0 + w) × [y0, y0 + h)` (clipped).
    pub fn fill_rect(&mut self, x0: i64, y0: i64, w: i64, h: i64, c: [u8; 3]) {
        for y in y0.max(0)..(y0 + h).min(self.height as i64) {
            for x in x0.max(0)..(x0 + w).min(self.width as i64) {
                self.put(x as usize, y as usize, c);
            }
        }
    }

    /// Writes the image as a PNG file.
    ///
    /// # Errors
    /// [`RenderError::Io`] if the file cannot be created,
    /// [`RenderError::Encode`] if encoding fails.
    pub fn write_png(&self, path: &Path) -> Result<()> {
        let file = std::fs::File::create(path).map_err(|e| RenderError::io(path, e))?;
        let enc_err = |e: png::EncodingError| match e {
            png::EncodingError::IoError(io) => RenderError::io(path, io),
            other => RenderError::Encode {
                path: path.to_owned(),
                message: other.to_string(),
            },
        };
        let mut enc = png::Encoder::new(BufWriter::new(file), self.width, self.height);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        enc.set_compression(png::Compression::High);
        let mut writer = enc.write_header().map_err(enc_err)?;
        writer.write_image_data(&self.data).map_err(enc_err)?;
        writer.finish().map_err(enc_err)?;
        Ok(())
    }

    /// Reads a PNG file (8-bit RGB or RGBA; alpha is dropped).
    ///
    /// # Errors
    /// [`RenderError::Io`] if it cannot be read, [`RenderError::Format`] if
    /// it is not such a PNG.
    pub fn read_png(path: &Path) -> Result<Self> {
        let file = std::fs::File::open(path).map_err(|e| RenderError::io(path, e))?;
        let bad = |m: String| RenderError::format(path, m);
        let dec = png::Decoder::new(std::io::BufReader::new(file));
        let mut reader = dec.read_info().map_err(|e| bad(e.to_string()))?;
        let size = reader
            .output_buffer_size()
            .ok_or_else(|| bad("image too large".into()))?;
        let mut buf = vec![0; size];
        let info = reader
            .next_frame(&mut buf)
            .map_err(|e| bad(e.to_string()))?;
        if info.bit_depth != png::BitDepth::Eight {
            return Err(bad("not an 8-bit PNG".into()));
        }
        let data = match info.color_type {
            png::ColorType::Rgb => buf[..info.buffer_size()].to_vec(),
            png::ColorType::Rgba => buf[..info.buffer_size()]
                .chunks_exact(4)
                .flat_map(|p| [p[0], p[1], p[2]])
                .collect(),
            other => return Err(bad(format!("unsupported PNG colour type {other:?}"))),
        };
        Ok(Self {
            width: info.width,
            height: info.height,
            data,
        })
    }

    /// Copies `src` into this image with its top-left corner at `(x0, y0)`
    /// (clipped).
    pub fn paste(&mut self, src: &RgbImage, x0: usize, y0: usize) {
        for y in 0..src.height as usize {
            for x in 0..src.width as usize {
                let i = 3 * (y * src.width as usize + x);
                self.put(
                    x0 + x,
                    y0 + y,
                    [src.data[i], src.data[i + 1], src.data[i + 2]],
                );
            }
        }
    }
}
