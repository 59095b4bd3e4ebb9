//! 8-bit grey PNG files, read and written, and 8-bit colour ones written
//! (for figures).

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

/// Writes `rgb` (`width × height` pixels, row-major, three bytes each:
/// red, green, blue) as an 8-bit colour PNG.
///
/// # Errors
/// [`VisionError::Png`] naming the file when `rgb` is not `3 · width ·
/// height` bytes or a side is too large; [`VisionError::Io`] when the
/// file cannot be written.
pub fn write_png_rgb(
    path: &Path,
    width: usize,
    height: usize,
    rgb: &[u8],
) -> Result<(), VisionError> {
    if rgb.len() != 3 * width * height {
        return Err(png_error(
            path,
            format!(
                "{} bytes for {width} × {height} colour pixels; expected {}",
                rgb.len(),
                3 * width * height
            ),
        ));
    }
    write_png(path, width, height, png::ColorType::Rgb, rgb)
}

/// Writes `image` as an 8-bit grey PNG.
///
/// # Errors
/// [`VisionError::Io`] or [`VisionError::Png`] naming the file.
pub fn write_png_gray(path: &Path, image: &GrayImage) -> Result<(), VisionError> {
    write_png(
        path,
        image.width(),
        image.height(),
        png::ColorType::Grayscale,
        image.pixels(),
    )
}

fn write_png(
    path: &Path,
    width: usize,
    height: usize,
    color: png::ColorType,
    data: &[u8],
) -> Result<(), VisionError> {
    let shape = |n: usize| {
        u32::try_from(n).map_err(|_| png_error(path, format!("a side of {n} pixels is too large")))
    };
    let file = File::create(path).map_err(|e| io_error(path, e))?;
    let mut encoder = png::Encoder::new(BufWriter::new(file), shape(width)?, shape(height)?);
    encoder.set_color(color);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().map_err(|e| png_error(path, e))?;
    writer
        .write_image_data(data)
        .map_err(|e| png_error(path, e))?;
    writer.finish().map_err(|e| png_error(path, e))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_colour_image_reads_back_byte_for_byte() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("rgb.png");
        let (w, h) = (5, 3);
        let rgb: Vec<u8> = (0..3 * w * h).map(|k| (k * 17 % 256) as u8).collect();
        write_png_rgb(&path, w, h, &rgb).unwrap();
        let decoder = png::Decoder::new(BufReader::new(File::open(&path).unwrap()));
        let mut reader = decoder.read_info().unwrap();
        assert_eq!(
            reader.output_color_type(),
            (png::ColorType::Rgb, png::BitDepth::Eight)
        );
        let mut buffer = vec![0; reader.output_buffer_size()];
        let frame = reader.next_frame(&mut buffer).unwrap();
        assert_eq!((frame.width, frame.height), (w as u32, h as u32));
        assert_eq!(&buffer[..rgb.len()], &rgb[..]);
        let wrong = write_png_rgb(&path, w, h + 1, &rgb)
            .unwrap_err()
            .to_string();
        assert!(
            wrong.contains("rgb.png") && wrong.contains("expected 60"),
            "{wrong}"
        );
    }
}
