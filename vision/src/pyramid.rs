//! Scale pyramids and the filters ORB needs: bilinear resampling (the
//! pixel-centre convention of OpenCV's `INTER_LINEAR`) and a separable
//! Gaussian blur with mirrored borders (`BORDER_REFLECT_101`).

use pulp::{Arch, Simd, WithSimd};

use crate::GrayImage;

/// An image at several scales: level `l` is the original shrunk by
/// `scale_factor^l`, each level resampled from the one before.
#[derive(Debug, Clone, PartialEq)]
pub struct Pyramid {
    /// The levels, from the original.
    pub levels: Vec<GrayImage>,
    /// Each level's scale: original pixels per level pixel.
    pub scales: Vec<f64>,
}

impl Pyramid {
    /// The pyramid of `image` with `levels` levels (at least 1), each
    /// `scale_factor` (> 1) smaller than the one before, sizes rounded.
    pub fn new(image: &GrayImage, levels: usize, scale_factor: f64) -> Self {
        let mut out = Self {
            levels: vec![image.clone()],
            scales: vec![1.0],
        };
        for l in 1..levels.max(1) {
            let scale = scale_factor.powi(l as i32);
            let w = ((image.width() as f64 / scale).round() as usize).max(1);
            let h = ((image.height() as f64 / scale).round() as usize).max(1);
            let below = &out.levels[l - 1];
            out.levels.push(resize_bilinear(below, w, h));
            out.scales.push(scale);
        }
        out
    }
}

/// `image` resampled to `width × height` by bilinear interpolation, the
/// destination pixel `(x, y)` taken at `((x + ½) s_x − ½, (y + ½) s_y − ½)`
/// of the source, clamped to its edge, rounded to the nearest grey level.
pub fn resize_bilinear(image: &GrayImage, width: usize, height: usize) -> GrayImage {
    Arch::new().dispatch(Resize {
        image,
        width,
        height,
    })
}

/// [`resize_bilinear`] on the processor's widest vectors.
struct Resize<'a> {
    image: &'a GrayImage,
    width: usize,
    height: usize,
}

impl WithSimd for Resize<'_> {
    type Output = GrayImage;

    #[inline(always)]
    fn with_simd<S: Simd>(self, _: S) -> GrayImage {
        resize_bilinear_here(self.image, self.width, self.height)
    }
}

/// [`resize_bilinear`], inlined into its caller's target features.
#[inline(always)]
fn resize_bilinear_here(image: &GrayImage, width: usize, height: usize) -> GrayImage {
    let (sw, sh) = (image.width(), image.height());
    let (sx, sy) = (sw as f64 / width as f64, sh as f64 / height as f64);
    // Source index and weight of the right/lower neighbour, per column/row.
    let taps = |n: usize, s: f64, limit: usize| -> Vec<(usize, usize, f32)> {
        (0..n)
            .map(|k| {
                let c = ((k as f64 + 0.5) * s - 0.5).clamp(0.0, (limit - 1) as f64);
                let i = c as usize;
                let next = (i + 1).min(limit - 1);
                (i, next, (c - i as f64) as f32)
            })
            .collect()
    };
    let (cols, rows) = (taps(width, sx, sw), taps(height, sy, sh));
    let mut pixels = Vec::with_capacity(width * height);
    for &(j0, j1, wy) in &rows {
        let (r0, r1) = (image.row(j0), image.row(j1));
        for &(i0, i1, wx) in &cols {
            let top = f32::from(r0[i0]) + (f32::from(r0[i1]) - f32::from(r0[i0])) * wx;
            let bottom = f32::from(r1[i0]) + (f32::from(r1[i1]) - f32::from(r1[i0])) * wx;
            // Truncating `v + ½` rounds a non-negative `v` as `round` does,
            // without a call to the C library's `round`.
            pixels.push((top + (bottom - top) * wy + 0.5).clamp(0.0, 255.0) as u8);
        }
    }
    GrayImage::from_pixels(width, height, pixels)
        .unwrap_or_else(|_| GrayImage::filled(width, height, 0))
}

/// The index `k` reflected into `0..n` without repeating the edge
/// (`BORDER_REFLECT_101`: `-1 → 1`, `n → n − 2`).
fn reflect_101(k: isize, n: usize) -> usize {
    let n = n as isize;
    if n == 1 {
        return 0;
    }
    let period = 2 * (n - 1);
    let k = k.rem_euclid(period);
    (if k < n { k } else { period - k }) as usize
}

/// `image` blurred by a Gaussian of standard deviation `sigma` over a
/// `(2 radius + 1)²` window (normalised weights; rows, then columns),
/// mirrored at the borders, rounded to the nearest grey level.
pub fn gaussian_blur(image: &GrayImage, radius: usize, sigma: f64) -> GrayImage {
    Arch::new().dispatch(Blur {
        image,
        radius,
        sigma,
    })
}

/// [`gaussian_blur`] on the processor's widest vectors.
struct Blur<'a> {
    image: &'a GrayImage,
    radius: usize,
    sigma: f64,
}

impl WithSimd for Blur<'_> {
    type Output = GrayImage;

    #[inline(always)]
    fn with_simd<S: Simd>(self, _: S) -> GrayImage {
        gaussian_blur_here(self.image, self.radius, self.sigma)
    }
}

/// [`gaussian_blur`], inlined into its caller's target features (the
/// sums' operations and their order do not depend on them).
#[inline(always)]
fn gaussian_blur_here(image: &GrayImage, radius: usize, sigma: f64) -> GrayImage {
    let (w, h) = (image.width(), image.height());
    let r = radius as isize;
    let mut weights: Vec<f32> = (-r..=r)
        .map(|k| (-(k * k) as f64 / (2.0 * sigma * sigma)).exp() as f32)
        .collect();
    let total: f32 = weights.iter().sum();
    weights.iter_mut().for_each(|v| *v /= total);
    // Each output row's source rows, mirrored at the borders.
    let down_taps: Vec<usize> = (0..h as isize)
        .flat_map(|i| (-r..=r).map(move |k| reflect_101(i + k, h)))
        .collect();
    let span = 2 * radius + 1;
    // Across: each row padded by its mirror image, then summed tap by tap
    // over the whole row (the same additions in the same order as a sum
    // per pixel, in loops the compiler vectorises).
    let mut across = vec![0f32; w * h];
    let mut padded = vec![0f32; w + 2 * radius];
    for y in 0..h {
        let row = image.row(y);
        for (i, p) in padded.iter_mut().enumerate() {
            *p = f32::from(row[reflect_101(i as isize - r, w)]);
        }
        let out = &mut across[y * w..(y + 1) * w];
        for (k, wk) in weights.iter().enumerate() {
            for (acc, v) in out.iter_mut().zip(&padded[k..k + w]) {
                *acc += wk * v;
            }
        }
    }
    let mut pixels = vec![0u8; w * h];
    let mut column = vec![0f32; w];
    for y in 0..h {
        column.iter_mut().for_each(|v| *v = 0.0);
        let sources = &down_taps[y * span..(y + 1) * span];
        for (wk, &j) in weights.iter().zip(sources) {
            for (acc, v) in column.iter_mut().zip(&across[j * w..(j + 1) * w]) {
                *acc += wk * v;
            }
        }
        for (out, v) in pixels[y * w..(y + 1) * w].iter_mut().zip(&column) {
            *out = (v + 0.5).clamp(0.0, 255.0) as u8;
        }
    }
    GrayImage::from_pixels(w, h, pixels).unwrap_or_else(|_| GrayImage::filled(w, h, 0))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ramp(w: usize, h: usize) -> GrayImage {
        let pixels = (0..w * h).map(|k| ((k % w) * 2 + (k / w)) as u8).collect();
        GrayImage::from_pixels(w, h, pixels).unwrap()
    }

    #[test]
    fn reflection_does_not_repeat_the_edge() {
        let got: Vec<usize> = (-3..8).map(|k| reflect_101(k, 5)).collect();
        assert_eq!(got, vec![3, 2, 1, 0, 1, 2, 3, 4, 3, 2, 1]);
    }

    #[test]
    fn a_ramp_survives_blur_and_halving_as_a_ramp() {
        let image = ramp(40, 30);
        // A linear ramp is a fixed point of a symmetric blur inside.
        let blurred = gaussian_blur(&image, 3, 2.0);
        for y in 3..27 {
            for x in 3..37 {
                assert_eq!(blurred.get(x, y), image.get(x, y));
            }
        }
        // Halving takes each 2 × 2 block's centre: the ramp's value there.
        let half = resize_bilinear(&image, 20, 15);
        for y in 0..15 {
            for x in 0..20 {
                let expected = (2.0 * (2 * x) as f64 + 1.0 + (2 * y) as f64 + 0.5).round();
                assert_eq!(f64::from(half.get(x, y)), expected, "({x}, {y})");
            }
        }
    }

    #[test]
    fn the_pyramid_shrinks_by_the_factor() {
        let pyramid = Pyramid::new(&ramp(100, 60), 4, 1.2);
        let sizes: Vec<(usize, usize)> = pyramid
            .levels
            .iter()
            .map(|l| (l.width(), l.height()))
            .collect();
        assert_eq!(sizes, vec![(100, 60), (83, 50), (69, 42), (58, 35)]);
    }
}
