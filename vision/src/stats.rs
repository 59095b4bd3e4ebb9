//! The statistics a rendered soil is compared with a real image by: the
//! spread of its grey levels and the density of its FAST corners, in a
//! box of pixels.

use crate::fast::{count_in, detect};
use crate::{GrayImage, PixelBox, VisionError};

/// The grey levels of a box: mean and standard deviation (population).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GreyLevels {
    /// Mean grey level.
    pub mean: f64,
    /// Standard deviation of the grey levels (divides by the count).
    pub std: f64,
}

/// The grey levels of `region` of `image`.
///
/// # Errors
/// [`VisionError::Shape`] when the box is empty or leaves the image.
pub fn grey_levels(image: &GrayImage, region: &PixelBox) -> Result<GreyLevels, VisionError> {
    let crop = image.crop(region)?;
    let n = crop.pixels().len() as f64;
    let mean = crop.pixels().iter().map(|&v| f64::from(v)).sum::<f64>() / n;
    let var = crop
        .pixels()
        .iter()
        .map(|&v| (f64::from(v) - mean).powi(2))
        .sum::<f64>()
        / n;
    Ok(GreyLevels {
        mean,
        std: var.sqrt(),
    })
}

/// FAST-9 corners (non-maximum suppressed) per 10⁴ pixels of `region`,
/// detected on the whole image at `threshold` (so a corner near the box's
/// edge sees the pixels beyond it, as a tracker's would).
///
/// # Errors
/// [`VisionError::Shape`] when the box is empty or leaves the image.
pub fn corner_density(
    image: &GrayImage,
    region: &PixelBox,
    threshold: u8,
) -> Result<f64, VisionError> {
    region.check_within(image)?;
    let corners = detect(image, threshold, true);
    Ok(count_in(&corners, region) as f64 * 1e4 / region.area() as f64)
}
