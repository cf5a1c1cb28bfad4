//! Depth frames: u16 millimetres per pixel, row-major, 0 = no measurement; PNG-16 files
//! (16-bit greyscale, the value is the depth in millimetres, as tools and most datasets write them).

use crate::error::KinectError;
use std::path::Path;

/// One depth image: `data_mm[v * width + u]` is the depth (z, millimetres) at column `u`, row `v`;
/// 0 means no measurement.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DepthFrame {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Depth per pixel in millimetres, row-major from the top-left pixel.
    pub data_mm: Vec<u16>,
}

impl DepthFrame {
    /// A frame, checking that `data_mm` has `width × height` values.
    pub fn new(width: u32, height: u32, data_mm: Vec<u16>) -> Result<DepthFrame, KinectError> {
        let expected = width as usize * height as usize;
        if data_mm.len() != expected || expected == 0 {
            return Err(KinectError::DepthSize {
                width,
                height,
                values: data_mm.len(),
                expected: format!("{expected} (> 0) values"),
            });
        }
        Ok(DepthFrame {
            width,
            height,
            data_mm,
        })
    }

    /// Depth in millimetres at column `u`, row `v` (`None` outside the image).
    pub fn at(&self, u: u32, v: u32) -> Option<u16> {
        if u < self.width && v < self.height {
            self.data_mm
                .get(v as usize * self.width as usize + u as usize)
                .copied()
        } else {
            None
        }
    }
}

/// Reads a 16-bit greyscale PNG as a depth frame (values in millimetres).
///
/// Errors: [`KinectError::Io`], [`KinectError::Png`] for a malformed PNG or one that is not
/// 16-bit single-channel.
pub fn read_depth_png16(path: impl AsRef<Path>) -> Result<DepthFrame, KinectError> {
    let file = path.as_ref().display().to_string();
    let bytes = crate::error::read_input(path.as_ref())?;
    decode_depth_png16(&bytes, &file)
}

/// The width and height of a PNG file, from its header alone (the image data is not read):
/// a recording checks its frames' size against its intrinsics before decoding any.
///
/// Errors: [`KinectError::Io`], [`KinectError::Png`] for a file without a readable PNG header.
pub(crate) fn png_size(path: impl AsRef<Path>) -> Result<(u32, u32), KinectError> {
    let path = path.as_ref();
    let file = std::fs::File::open(path).map_err(|source| KinectError::Io {
        file: path.display().to_string(),
        source,
    })?;
    let reader = png::Decoder::new(std::io::BufReader::new(file))
        .read_info()
        .map_err(|e| KinectError::Png {
            file: path.display().to_string(),
            message: format!("not a readable PNG: {e}"),
        })?;
    let info = reader.info();
    Ok((info.width, info.height))
}

/// Decodes PNG bytes as a depth frame; `file` names the source in errors.
pub fn decode_depth_png16(bytes: &[u8], file: &str) -> Result<DepthFrame, KinectError> {
    let perr = |message: String| KinectError::Png {
        file: file.to_string(),
        message,
    };
    let mut decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    // Keep 16-bit samples as they are (no stripping, no expansion).
    decoder.set_transformations(png::Transformations::IDENTITY);
    let mut reader = decoder
        .read_info()
        .map_err(|e| perr(format!("not a readable PNG: {e}")))?;
    let info = reader.info();
    let (width, height) = (info.width, info.height);
    if info.color_type != png::ColorType::Grayscale || info.bit_depth != png::BitDepth::Sixteen {
        return Err(perr(format!(
            "expected a 16-bit greyscale PNG (depth in mm), found {:?} with {:?}-bit samples",
            info.color_type, info.bit_depth as u8
        )));
    }
    // Refuse absurd sizes before allocating (a 16k × 16k depth image is already far beyond any sensor).
    if width as u64 * height as u64 > (1 << 28) {
        return Err(perr(format!(
            "image {width}x{height} is too large for a depth frame"
        )));
    }
    let mut buf = vec![0u8; reader.output_buffer_size().unwrap_or(0)];
    let out = reader
        .next_frame(&mut buf)
        .map_err(|e| perr(format!("corrupt image data: {e}")))?;
    let row = out.line_size;
    let mut data = Vec::with_capacity(width as usize * height as usize);
    for v in 0..height as usize {
        let line = &buf[v * row..v * row + 2 * width as usize];
        data.extend(
            line.chunks_exact(2)
                .map(|c| u16::from_be_bytes([c[0], c[1]])),
        );
    }
    DepthFrame::new(width, height, data)
}

/// Writes a depth frame as a 16-bit greyscale PNG, atomically (temporary file + rename).
pub fn write_depth_png16(path: impl AsRef<Path>, frame: &DepthFrame) -> Result<(), KinectError> {
    let bytes = encode_depth_png16(frame)?;
    crate::atomic_write(path.as_ref(), &bytes)
}

/// Encodes a depth frame as 16-bit greyscale PNG bytes.
pub fn encode_depth_png16(frame: &DepthFrame) -> Result<Vec<u8>, KinectError> {
    DepthFrame::new(frame.width, frame.height, frame.data_mm.clone())?;
    let mut out = Vec::new();
    let perr = |e: png::EncodingError| KinectError::Png {
        file: "<memory>".into(),
        message: e.to_string(),
    };
    {
        let mut enc = png::Encoder::new(&mut out, frame.width, frame.height);
        enc.set_color(png::ColorType::Grayscale);
        enc.set_depth(png::BitDepth::Sixteen);
        let mut w = enc.write_header().map_err(perr)?;
        let bytes: Vec<u8> = frame.data_mm.iter().flat_map(|d| d.to_be_bytes()).collect();
        w.write_image_data(&bytes).map_err(perr)?;
        w.finish().map_err(perr)?;
    }
    Ok(out)
}
