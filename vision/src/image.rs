//! An 8-bit grey image, row-major, and an axis-aligned box of its pixels.

use crate::VisionError;

/// An 8-bit grey image, row-major (`pixels[y * width + x]`), `x` to the
/// right and `y` down from the top-left pixel.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct GrayImage {
    width: usize,
    height: usize,
    pixels: Vec<u8>,
}

impl GrayImage {
    /// An image of `width × height` pixels, all `value`.
    pub fn filled(width: usize, height: usize, value: u8) -> Self {
        Self {
            width,
            height,
            pixels: vec![value; width * height],
        }
    }

    /// An image from row-major pixels.
    ///
    /// # Errors
    /// [`VisionError::Shape`] when `pixels` does not hold `width × height`
    /// values.
    pub fn from_pixels(width: usize, height: usize, pixels: Vec<u8>) -> Result<Self, VisionError> {
        if pixels.len() != width * height {
            return Err(VisionError::Shape {
                what: "grey image".into(),
                detail: format!(
                    "{} pixels for {width} × {height}; expected {}",
                    pixels.len(),
                    width * height
                ),
            });
        }
        Ok(Self {
            width,
            height,
            pixels,
        })
    }

    /// Width (pixels).
    pub fn width(&self) -> usize {
        self.width
    }

    /// Height (pixels).
    pub fn height(&self) -> usize {
        self.height
    }

    /// The pixels, row-major.
    pub fn pixels(&self) -> &[u8] {
        &self.pixels
    }

    /// The pixels, row-major, to write.
    pub fn pixels_mut(&mut self) -> &mut [u8] {
        &mut self.pixels
    }

    /// The pixel at column `x`, row `y` (panics outside the image, as
    /// slice indexing does).
    pub fn get(&self, x: usize, y: usize) -> u8 {
        self.pixels[y * self.width + x]
    }

    /// Sets the pixel at column `x`, row `y`.
    pub fn set(&mut self, x: usize, y: usize, value: u8) {
        self.pixels[y * self.width + x] = value;
    }

    /// Row `y`.
    pub fn row(&self, y: usize) -> &[u8] {
        &self.pixels[y * self.width..(y + 1) * self.width]
    }

    /// A copy of the pixels inside `region`.
    ///
    /// # Errors
    /// [`VisionError::Shape`] when `region` is empty or leaves the image.
    pub fn crop(&self, region: &PixelBox) -> Result<Self, VisionError> {
        region.check_within(self)?;
        let mut pixels = Vec::with_capacity(region.width * region.height);
        for y in region.y..region.y + region.height {
            pixels.extend_from_slice(&self.row(y)[region.x..region.x + region.width]);
        }
        Self::from_pixels(region.width, region.height, pixels)
    }
}

/// An axis-aligned box of pixels: its top-left pixel and its size.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PixelBox {
    /// Column of the top-left pixel.
    pub x: usize,
    /// Row of the top-left pixel.
    pub y: usize,
    /// Width (pixels).
    pub width: usize,
    /// Height (pixels).
    pub height: usize,
}

impl PixelBox {
    /// The whole of `image`.
    pub fn whole(image: &GrayImage) -> Self {
        Self {
            x: 0,
            y: 0,
            width: image.width(),
            height: image.height(),
        }
    }

    /// The number of pixels in the box.
    pub fn area(&self) -> usize {
        self.width * self.height
    }

    /// Whether the pixel at `(x, y)` is inside the box.
    pub fn contains(&self, x: usize, y: usize) -> bool {
        (self.x..self.x + self.width).contains(&x) && (self.y..self.y + self.height).contains(&y)
    }

    /// # Errors
    /// [`VisionError::Shape`] when the box is empty or leaves `image`.
    pub(crate) fn check_within(&self, image: &GrayImage) -> Result<(), VisionError> {
        if self.width == 0
            || self.height == 0
            || self.x + self.width > image.width()
            || self.y + self.height > image.height()
        {
            return Err(VisionError::Shape {
                what: format!(
                    "box {}×{} at ({}, {})",
                    self.width, self.height, self.x, self.y
                ),
                detail: format!(
                    "expected a non-empty box inside the {} × {} image",
                    image.width(),
                    image.height()
                ),
            });
        }
        Ok(())
    }
}
