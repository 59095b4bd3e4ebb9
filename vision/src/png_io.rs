//! 8-bit grey PNG files, read and written.

use std::fs::File;
use std::io::{BufReader, BufWriter};
use std::path::Path;

use crate::{GrayImage, VisionError};

fn png_error(path: &Path, detail: impl ToString) -> VisionError {
    VisionError::Png {
        path: path.to_path_buf(),
        detail: detail.to_string(),
    }
}

fn io_error(path: &Path, source: std::io::Error) -> VisionError {
    VisionError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// Reads an 8-bit grey PNG.
///
/// # Errors
/// [`VisionError::Io`] when the file cannot be opened;
/// [`VisionError::Png`] when it is not a PNG, or not 8-bit grey.
pub fn read_png_gray(path: &Path) -> Result<GrayImage, VisionError> {
    let file = File::open(path).map_err(|e| io_error(path, e))?;
    let decoder = png::Decoder::new(BufReader::new(file));
    let mut reader = decoder.read_info().map_err(|e| png_error(path, e))?;
    let (color, depth) = reader.output_color_type();
    if color != png::ColorType::Grayscale || depth != png::BitDepth::Eight {
        return Err(png_error(
            path,
            format!("{color:?} at {depth:?}; expected 8-bit grey (Grayscale, Eight)"),
        ));
    }
    let mut buffer = vec![0; reader.output_buffer_size()];
    let frame = reader
        .next_frame(&mut buffer)
        .map_err(|e| png_error(path, e))?;
    let (width, height) = (frame.width as usize, frame.height as usize);
    let mut pixels = Vec::with_capacity(width * height);
    for row in buffer.chunks(frame.line_size).take(height) {
        pixels.extend_from_slice(&row[..width]);
    }
    GrayImage::from_pixels(width, height, pixels)
}

/// Writes `image` as an 8-bit grey PNG.
///
/// # Errors
/// [`VisionError::Io`] or [`VisionError::Png`] naming the file.
pub fn write_png_gray(path: &Path, image: &GrayImage) -> Result<(), VisionError> {
    let shape = |n: usize| {
        u32::try_from(n).map_err(|_| png_error(path, format!("a side of {n} pixels is too large")))
    };
    let file = File::create(path).map_err(|e| io_error(path, e))?;
    let mut encoder = png::Encoder::new(
        BufWriter::new(file),
        shape(image.width())?,
        shape(image.height())?,
    );
    encoder.set_color(png::ColorType::Grayscale);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().map_err(|e| png_error(path, e))?;
    writer
        .write_image_data(image.pixels())
        .map_err(|e| png_error(path, e))?;
    writer.finish().map_err(|e| png_error(path, e))
}
