//! Stereo matching against a closed form: a textured plane parallel to
//! the image, seen by the right camera shifted by a known disparity.

#![allow(clippy::unwrap_used)]

use gpodo_vision::GrayImage;
use gpodo_vision::orb::OrbParams;
use gpodo_vision::stereo::stereo_features;

/// An analytic texture, so that a fractional shift is exact.
fn texture(x: f64, y: f64) -> f64 {
    110.0
        + 40.0 * (0.21 * x + 0.05 * y).sin() * (0.17 * y - 0.03 * x).cos()
        + 25.0 * (0.53 * x - 0.41 * y).sin()
        + 20.0 * (0.9 * y + 0.3 * x).cos() * (0.07 * x).sin()
}

fn image(width: usize, height: usize, shift: f64) -> GrayImage {
    let pixels = (0..width * height)
        .map(|k| {
            let (x, y) = ((k % width) as f64, (k / width) as f64);
            texture(x + shift, y).round().clamp(0.0, 255.0) as u8
        })
        .collect();
    GrayImage::from_pixels(width, height, pixels).unwrap()
}

#[test]
fn a_fronto_parallel_plane_gives_its_disparity_within_a_seventh_of_a_pixel() {
    for disparity in [12.0, 7.4] {
        let (left, right) = (image(320, 240, 0.0), image(320, 240, disparity));
        let params = OrbParams::exoter_for_size(320, 240);
        let stereo = stereo_features(&left, &right, &params, 300.0).unwrap();
        let n = stereo.left.keypoints.len();
        // The two images' quadtrees keep different corners of the same
        // texture, so not every left keypoint has its twin on the right.
        assert!(
            stereo.matched() * 3 > n,
            "{} of {n} matched",
            stereo.matched()
        );
        let mut errors: Vec<f64> = (0..n)
            .filter_map(|k| stereo.disparity(k))
            .map(|d| (f64::from(d) - disparity).abs())
            .collect();
        errors.sort_by(f64::total_cmp);
        let median = errors[errors.len() / 2];
        // A parabola through window distances locks towards whole pixels
        // by about a tenth of one.
        assert!(
            median < 0.15,
            "disparity {disparity}: median error {median}"
        );
        // Coarse levels' matches err more, in original pixels; a periodic
        // texture fools a few descriptors (PnP's RANSAC and the robust
        // refinement are there for them): 97 % are within two pixels of
        // the top level.
        let near = errors.iter().filter(|e| **e < 2.0 * 1.2f64.powi(7)).count();
        assert!(near * 100 >= errors.len() * 97, "{errors:?}");
    }
}

#[test]
fn a_pair_of_different_sizes_is_refused() {
    let params = OrbParams::exoter_for_size(320, 240);
    let err = stereo_features(&image(320, 240, 0.0), &image(300, 240, 0.0), &params, 300.0);
    assert!(err.is_err());
}
