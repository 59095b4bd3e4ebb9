//! Stereo matching of ORB features along the rows of a rectified pair, as
//! ORB-SLAM2's `Frame::ComputeStereoMatches` does it:
//!
//! 1. each left keypoint is compared with the right keypoints on its row
//!    (within `2 s` pixels, `s` the right keypoint's scale), of a
//!    neighbouring pyramid level, at a disparity in `[0, f]` (depths from
//!    the baseline on); the best Hamming distance must be below 75 (the
//!    mean of ORB-SLAM2's `TH_HIGH` 100 and `TH_LOW` 50);
//! 2. the match is refined on the keypoint's pyramid level by the sum of
//!    absolute differences of 11 × 11 windows, each less its centre pixel,
//!    slid ±5 pixels along the row; a best shift at either end is
//!    rejected, and a parabola through the best and its two neighbours
//!    gives the sub-pixel shift (rejected beyond one pixel);
//! 3. matches whose window distance exceeds `1.5 · 1.4 ·` the median
//!    (`1.4` scaling the median to a standard deviation) are dropped.

use crate::orb::{Features, OrbParams, extract_from_pyramid, hamming, to_level, to_original};
use crate::pyramid::Pyramid;
use crate::{GrayImage, VisionError};

/// Hamming distance below which a stereo match is refined.
const MAX_DESCRIPTOR_DISTANCE: u32 = 75;
/// Half-side of the refinement window (pixels of the level).
const WINDOW: isize = 5;
/// Shifts tried on either side of the descriptor match.
const SLIDE: isize = 5;

/// A rectified stereo frame's features: the left image's ORB features,
/// and for each the right image's sub-pixel column where it was matched.
#[derive(Debug, Clone, PartialEq)]
pub struct StereoFeatures {
    /// The left image's features.
    pub left: Features,
    /// Per left keypoint: the matched right column (original pixels), or
    /// `None`.
    pub right_x: Vec<Option<f32>>,
}

impl StereoFeatures {
    /// The disparity of left keypoint `k` (pixels), when matched.
    pub fn disparity(&self, k: usize) -> Option<f32> {
        self.right_x[k].map(|r| self.left.keypoints[k].x - r)
    }

    /// How many left keypoints have a right match.
    pub fn matched(&self) -> usize {
        self.right_x.iter().flatten().count()
    }
}

/// The ORB features of both images of a rectified pair and their row
/// matches, for a camera of focal length `focal_px` (the largest
/// disparity searched).
///
/// # Errors
/// [`VisionError::InvalidParameter`] for bad settings;
/// [`VisionError::Shape`] when the images differ in size.
pub fn stereo_features(
    left: &GrayImage,
    right: &GrayImage,
    params: &OrbParams,
    focal_px: f64,
) -> Result<StereoFeatures, VisionError> {
    params.validate()?;
    if (left.width(), left.height()) != (right.width(), right.height()) {
        return Err(VisionError::Shape {
            what: "stereo pair".into(),
            detail: format!(
                "left is {}×{}, right {}×{}",
                left.width(),
                left.height(),
                right.width(),
                right.height()
            ),
        });
    }
    let pyramids =
        [left, right].map(|image| Pyramid::new(image, params.levels, params.scale_factor));
    let features = [&pyramids[0], &pyramids[1]].map(|p| extract_from_pyramid(p, params));
    let [left_features, right_features] = features;
    let right_x = match_rows(&left_features, &right_features, &pyramids, focal_px);
    Ok(StereoFeatures {
        left: left_features,
        right_x,
    })
}

/// Step 1–3 of the module's matching.
fn match_rows(
    left: &Features,
    right: &Features,
    pyramids: &[Pyramid; 2],
    focal_px: f64,
) -> Vec<Option<f32>> {
    let height = pyramids[0].levels[0].height();
    // The right keypoints on each row's band.
    let mut rows: Vec<Vec<usize>> = vec![Vec::new(); height];
    for (k, kp) in right.keypoints.iter().enumerate() {
        let r = 2.0 * right.scales[usize::from(kp.level)] as f32;
        let (lo, hi) = (
            (kp.y - r).floor().max(0.0) as usize,
            (kp.y + r).ceil() as usize,
        );
        for row in rows.iter_mut().take(hi.min(height - 1) + 1).skip(lo) {
            row.push(k);
        }
    }
    let mut matches: Vec<Option<(f32, u32)>> = vec![None; left.keypoints.len()];
    for (k, kp) in left.keypoints.iter().enumerate() {
        let Some(candidates) = rows.get(kp.y.round() as usize) else {
            continue;
        };
        let (min_x, max_x) = (kp.x - focal_px as f32, kp.x);
        let best = candidates
            .iter()
            .filter(|&&c| {
                let r = &right.keypoints[c];
                r.level.abs_diff(kp.level) <= 1 && r.x >= min_x && r.x <= max_x
            })
            .map(|&c| (hamming(&left.descriptors[k], &right.descriptors[c]), c))
            .min();
        let Some((distance, c)) = best else { continue };
        if distance >= MAX_DESCRIPTOR_DISTANCE {
            continue;
        }
        matches[k] = refine(kp, right.keypoints[c].x, pyramids);
    }
    // Drop the matches whose window distance is far above the median.
    let mut distances: Vec<u32> = matches.iter().flatten().map(|m| m.1).collect();
    if distances.is_empty() {
        return vec![None; left.keypoints.len()];
    }
    distances.sort_unstable();
    let limit = 1.5 * 1.4 * f64::from(distances[distances.len() / 2]);
    matches
        .into_iter()
        .map(|m| m.filter(|m| f64::from(m.1) <= limit).map(|m| m.0))
        .collect()
}

/// The right column of `kp` refined by windows on its level, and the best
/// window distance; `None` when the best shift is at the slide's end, the
/// parabola's shift exceeds a pixel, or a window leaves the image.
fn refine(kp: &crate::orb::KeyPoint, right_x: f32, pyramids: &[Pyramid; 2]) -> Option<(f32, u32)> {
    let level = usize::from(kp.level);
    let scale = pyramids[0].scales[level] as f32;
    let (left, right) = (&pyramids[0].levels[level], &pyramids[1].levels[level]);
    let (ul, vl) = (
        to_level(kp.x, scale).round() as isize,
        to_level(kp.y, scale).round() as isize,
    );
    let ur = to_level(right_x, scale).round() as isize;
    let (w, h) = (left.width() as isize, left.height() as isize);
    let inside = |u: isize| u - WINDOW >= 0 && u + WINDOW < w;
    if !(inside(ul) && inside(ur - SLIDE) && inside(ur + SLIDE))
        || vl - WINDOW < 0
        || vl + WINDOW >= h
    {
        return None;
    }
    let centre_l = i32::from(left.get(ul as usize, vl as usize));
    let sad = |shift: isize| -> u32 {
        let u = ur + shift;
        let centre_r = i32::from(right.get(u as usize, vl as usize));
        let mut total = 0u32;
        for dv in -WINDOW..=WINDOW {
            let (row_l, row_r) = (left.row((vl + dv) as usize), right.row((vl + dv) as usize));
            for du in -WINDOW..=WINDOW {
                let a = i32::from(row_l[(ul + du) as usize]) - centre_l;
                let b = i32::from(row_r[(u + du) as usize]) - centre_r;
                total += (a - b).unsigned_abs();
            }
        }
        total
    };
    let distances: Vec<u32> = (-SLIDE..=SLIDE).map(sad).collect();
    let (best, &best_distance) = distances
        .iter()
        .enumerate()
        .min_by_key(|(k, d)| (**d, *k))?;
    if best == 0 || best == distances.len() - 1 {
        return None;
    }
    let (d1, d2, d3) = (
        f64::from(distances[best - 1]),
        f64::from(best_distance),
        f64::from(distances[best + 1]),
    );
    let curvature = d1 + d3 - 2.0 * d2;
    let delta = if curvature > 0.0 {
        (d1 - d3) / (2.0 * curvature)
    } else {
        0.0
    };
    if delta.abs() > 1.0 {
        return None;
    }
    let shift = (best as isize - SLIDE) as f64 + delta;
    Some((
        to_original((ur as f64 + shift) as f32, scale),
        best_distance,
    ))
}
