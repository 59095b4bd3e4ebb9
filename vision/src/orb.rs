//! ORB features (Rublee et al. 2011) as ORB-SLAM2's extractor computes
//! them: FAST-9 corners on a scale pyramid, spread over the image by a
//! grid and a quadtree, oriented by the intensity centroid, and described
//! by 256 binary tests of a rotated BRIEF pattern on the blurred level.
//!
//! * **Budget per level**: `N (1 − 1/s) / (1 − (1/s)^L) · (1/s)^l` of the
//!   `N` features at level `l`, the last level taking what is left.
//! * **Grid**: each level is cut into cells of 30 pixels; a cell keeps its
//!   FAST corners at `ini_threshold` (20 on ExoTeR), or at `min_threshold`
//!   (7) when it has none there. FAST runs once per level at the lower
//!   threshold: a corner's score does not depend on the threshold it is
//!   found at ([`crate::fast::score_map`]), and non-maximum suppression at
//!   the higher one ignores the neighbours below it.
//! * **Spread**: a quadtree splits the level's area until it has as many
//!   nodes as the level's budget, and each node keeps its best-scored
//!   corner (ORB-SLAM2's `DistributeOctTree`); the best `budget` of these
//!   are kept.
//! * **Orientation**: the angle of the intensity centroid
//!   `(m10, m01)` over the disc of radius 15 around the corner.
//! * **Descriptor**: on the level blurred by a 7 × 7 Gaussian of σ = 2,
//!   bit `k` is `I(p_k) < I(q_k)` for the `k`-th pair of the pattern
//!   rotated by the angle (coordinates rounded). The pattern is BRIEF's
//!   isotropic Gaussian one (Calonder et al. 2010, σ = 31/5) drawn once
//!   from a fixed seed inside the disc of radius 15, not ORB's learned
//!   table: descriptors compare with each other, not bit for bit with
//!   OpenCV's.
//!
//! Keypoints are at least 19 pixels from every edge of their level (the
//! rotated pattern stays inside), their positions given in the original
//! image's pixels with the pyramid's pixel-centre convention (ORB-SLAM2
//! multiplies by the scale, which moves a top-level keypoint by 1.3 px).

pub use crate::brief::Descriptor;
use crate::brief::{PATCH_RADIUS, describe};
use crate::fast::score_map;
use crate::pyramid::{Pyramid, gaussian_blur};
use crate::{GrayImage, VisionError};

/// Keypoints' distance from a level's edge (ORB-SLAM2's `EDGE_THRESHOLD`).
const EDGE: usize = 19;
/// Side of a grid cell (pixels of the level).
const CELL: usize = 30;

/// ORB extractor settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OrbParams {
    /// Features per image, over all levels.
    pub features: usize,
    /// Scale between pyramid levels.
    pub scale_factor: f64,
    /// Pyramid levels.
    pub levels: usize,
    /// FAST threshold tried first in every cell.
    pub ini_threshold: u8,
    /// FAST threshold of a cell with no corner at the first.
    pub min_threshold: u8,
}

impl OrbParams {
    /// ExoTeR's ORB-SLAM2 settings, for its 1024 × 768 Bumblebee2: 3000
    /// features, 8 levels of 1.2, FAST thresholds 20 then 7.
    pub fn exoter() -> Self {
        Self {
            features: 3000,
            scale_factor: 1.2,
            levels: 8,
            ini_threshold: 20,
            min_threshold: 7,
        }
    }

    /// ExoTeR's settings for a `width × height` image: the feature cap
    /// scaled with the pixel count (against 1024 × 768), and the levels cut
    /// so that the top one keeps at least 40 pixels of height.
    pub fn exoter_for_size(width: usize, height: usize) -> Self {
        let full = Self::exoter();
        let share = (width * height) as f64 / (1024.0 * 768.0);
        let mut levels = 1;
        while levels < full.levels && height as f64 / full.scale_factor.powi(levels as i32) >= 40.0
        {
            levels += 1;
        }
        Self {
            features: ((full.features as f64 * share).round() as usize).max(1),
            levels,
            ..full
        }
    }

    /// Checks every field.
    ///
    /// # Errors
    /// [`VisionError::InvalidParameter`] naming the field.
    pub fn validate(&self) -> Result<(), VisionError> {
        let bad = |field: &'static str, expected: &'static str| {
            Err(VisionError::InvalidParameter { field, expected })
        };
        if self.features == 0 {
            return bad("features", "at least 1");
        }
        if !(self.scale_factor.is_finite() && self.scale_factor > 1.0 && self.scale_factor <= 4.0) {
            return bad("scale_factor", "a factor in (1, 4]");
        }
        if !(1..=16).contains(&self.levels) {
            return bad("levels", "1 to 16 levels");
        }
        if self.min_threshold == 0 || self.min_threshold > self.ini_threshold {
            return bad("min_threshold", "a threshold in [1, ini_threshold]");
        }
        Ok(())
    }
}

/// An oriented keypoint.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KeyPoint {
    /// Column, in the original image's pixels.
    pub x: f32,
    /// Row, in the original image's pixels.
    pub y: f32,
    /// Pyramid level it was found at.
    pub level: u8,
    /// Orientation (rad, from the image's x axis towards its y axis).
    pub angle: f32,
    /// FAST score.
    pub score: u8,
}

pub use crate::hamming::hamming;

/// An image's features: keypoints and their descriptors, in step.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Features {
    /// The keypoints, level by level.
    pub keypoints: Vec<KeyPoint>,
    /// Their descriptors.
    pub descriptors: Vec<Descriptor>,
    /// Each level's scale (original pixels per level pixel).
    pub scales: Vec<f64>,
}

/// How many of `features` each of `levels` levels gets.
pub fn features_per_level(features: usize, levels: usize, scale_factor: f64) -> Vec<usize> {
    let factor = 1.0 / scale_factor;
    let first = features as f64 * (1.0 - factor) / (1.0 - factor.powi(levels as i32));
    let mut out = Vec::with_capacity(levels);
    let mut total = 0;
    for l in 0..levels.saturating_sub(1) {
        let n = (first * factor.powi(l as i32)).round() as usize;
        out.push(n);
        total += n;
    }
    out.push(features.saturating_sub(total));
    out
}

/// The ORB features of `image`.
///
/// # Errors
/// [`VisionError::InvalidParameter`] for bad settings.
pub fn extract(image: &GrayImage, params: &OrbParams) -> Result<Features, VisionError> {
    params.validate()?;
    let pyramid = Pyramid::new(image, params.levels, params.scale_factor);
    Ok(extract_from_pyramid(&pyramid, params))
}

/// The ORB features of the image whose pyramid is `pyramid` (built with
/// `params`' levels and scale factor; settings already checked).
pub fn extract_from_pyramid(pyramid: &Pyramid, params: &OrbParams) -> Features {
    let budgets = features_per_level(params.features, params.levels, params.scale_factor);
    let mut features = Features {
        scales: pyramid.scales.clone(),
        ..Features::default()
    };
    for (l, (level, &budget)) in pyramid.levels.iter().zip(&budgets).enumerate() {
        if level.width() <= 2 * EDGE || level.height() <= 2 * EDGE || budget == 0 {
            continue;
        }
        let corners = spread(grid_corners(level, params), level, budget);
        let blurred = gaussian_blur(level, 3, 2.0);
        let scale = pyramid.scales[l] as f32;
        for (x, y, score) in corners {
            let angle = centroid_angle(level, x, y);
            features.descriptors.push(describe(&blurred, x, y, angle));
            features.keypoints.push(KeyPoint {
                x: to_original(x as f32, scale),
                y: to_original(y as f32, scale),
                level: l as u8,
                angle,
                score,
            });
        }
    }
    features
}

/// The original image's coordinate of a level's pixel coordinate `c`,
/// pixel centres matched as the pyramid resamples them: `(c + ½) s − ½`.
pub fn to_original(c: f32, scale: f32) -> f32 {
    (c + 0.5) * scale - 0.5
}

/// A level's pixel coordinate of the original image's coordinate `c`.
pub fn to_level(c: f32, scale: f32) -> f32 {
    (c + 0.5) / scale - 0.5
}

/// The corners of each grid cell of `level`: at the first threshold, or
/// at the second where a cell has none at the first; `(x, y, score)`.
fn grid_corners(level: &GrayImage, params: &OrbParams) -> Vec<(usize, usize, u8)> {
    let (w, h) = (level.width(), level.height());
    let scores = score_map(level, params.min_threshold);
    let at = |x: usize, y: usize| scores[y * w + x];
    // A corner that is the strict maximum of its 8 neighbours, counting a
    // neighbour below `threshold` as no corner.
    let kept = |x: usize, y: usize, threshold: u8| {
        let s = at(x, y);
        s >= threshold
            && (y - 1..=y + 1).all(|j| {
                (x - 1..=x + 1).all(|i| {
                    let n = at(i, j);
                    (i == x && j == y) || n < threshold || s > n
                })
            })
    };
    let mut out = Vec::new();
    for y0 in (EDGE..h - EDGE).step_by(CELL) {
        for x0 in (EDGE..w - EDGE).step_by(CELL) {
            let (x1, y1) = ((x0 + CELL).min(w - EDGE), (y0 + CELL).min(h - EDGE));
            for threshold in [params.ini_threshold, params.min_threshold] {
                let before = out.len();
                for y in y0..y1 {
                    for x in x0..x1 {
                        if kept(x, y, threshold) {
                            out.push((x, y, at(x, y)));
                        }
                    }
                }
                if out.len() > before {
                    break;
                }
            }
        }
    }
    out
}

/// A node of the quadtree over a level's corners.
struct Node {
    x0: f64,
    y0: f64,
    x1: f64,
    y1: f64,
    corners: Vec<(usize, usize, u8)>,
}

impl Node {
    fn split(self) -> [Node; 4] {
        let (xm, ym) = (0.5 * (self.x0 + self.x1), 0.5 * (self.y0 + self.y1));
        let mut children = [
            (self.x0, self.y0, xm, ym),
            (xm, self.y0, self.x1, ym),
            (self.x0, ym, xm, self.y1),
            (xm, ym, self.x1, self.y1),
        ]
        .map(|(x0, y0, x1, y1)| Node {
            x0,
            y0,
            x1,
            y1,
            corners: Vec::new(),
        });
        for c in self.corners {
            let k = usize::from(c.0 as f64 >= xm) + 2 * usize::from(c.1 as f64 >= ym);
            children[k].corners.push(c);
        }
        children
    }
}

/// At most `budget` of `corners`, spread over the level by a quadtree:
/// nodes are split (those with the most corners first in the last round)
/// until there are `budget` of them or none can be split, and each keeps
/// its best-scored corner.
fn spread(
    corners: Vec<(usize, usize, u8)>,
    level: &GrayImage,
    budget: usize,
) -> Vec<(usize, usize, u8)> {
    let (x0, y0) = (EDGE as f64, EDGE as f64);
    let (x1, y1) = (
        (level.width() - EDGE) as f64,
        (level.height() - EDGE) as f64,
    );
    // Square-ish first nodes side by side.
    let columns = (((x1 - x0) / (y1 - y0)).round() as usize).max(1);
    let step = (x1 - x0) / columns as f64;
    let mut nodes: Vec<Node> = (0..columns)
        .map(|k| Node {
            x0: x0 + step * k as f64,
            y0,
            x1: x0 + step * (k + 1) as f64,
            y1,
            corners: Vec::new(),
        })
        .collect();
    for c in corners {
        let k = (((c.0 as f64 - x0) / step) as usize).min(columns - 1);
        nodes[k].corners.push(c);
    }
    nodes.retain(|n| !n.corners.is_empty());
    while nodes.len() < budget {
        let splittable = nodes.iter().filter(|n| n.corners.len() > 1).count();
        if splittable == 0 {
            break;
        }
        let last_round = nodes.len() + 3 * splittable >= budget;
        // The most crowded first (stable, so ties keep their order).
        nodes.sort_by_key(|n| std::cmp::Reverse(n.corners.len()));
        let mut next = Vec::with_capacity(nodes.len() + 3 * splittable);
        let mut count = nodes.len();
        for node in nodes {
            if node.corners.len() > 1 && !(last_round && count >= budget) {
                let children: Vec<Node> = node
                    .split()
                    .into_iter()
                    .filter(|c| !c.corners.is_empty())
                    .collect();
                count += children.len() - 1;
                next.extend(children);
            } else {
                next.push(node);
            }
        }
        nodes = next;
        if last_round {
            break;
        }
    }
    let mut best: Vec<(usize, usize, u8)> = nodes
        .iter()
        .filter_map(|n| {
            n.corners
                .iter()
                .copied()
                .max_by(|a, b| a.2.cmp(&b.2).then((b.1, b.0).cmp(&(a.1, a.0))))
        })
        .collect();
    // The best `budget`, highest score first, then in raster order.
    best.sort_by(|a, b| b.2.cmp(&a.2).then((a.1, a.0).cmp(&(b.1, b.0))));
    best.truncate(budget);
    best
}

/// The angle of the intensity centroid of the disc of radius 15 around
/// `(x, y)`: `atan2(m01, m10)` with `m_pq = Σ u^p v^q I(x + u, y + v)`.
pub fn centroid_angle(image: &GrayImage, x: usize, y: usize) -> f32 {
    let (mut m10, mut m01) = (0i64, 0i64);
    for v in -PATCH_RADIUS..=PATCH_RADIUS {
        let row = image.row(y.wrapping_add_signed(v));
        let reach = disc_reach(v);
        for u in -reach..=reach {
            let i = i64::from(row[x.wrapping_add_signed(u)]);
            m10 += u as i64 * i;
            m01 += v as i64 * i;
        }
    }
    (m01 as f64).atan2(m10 as f64) as f32
}

/// The half-width of the disc of radius 15 at row offset `v`.
fn disc_reach(v: isize) -> isize {
    let r2 = PATCH_RADIUS * PATCH_RADIUS;
    let mut u = 0;
    while (u + 1) * (u + 1) + v * v <= r2 {
        u += 1;
    }
    u
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_budget_is_a_geometric_series_that_sums_to_the_cap() {
        let n = features_per_level(3000, 8, 1.2);
        assert_eq!(n.iter().sum::<usize>(), 3000);
        assert_eq!(n[0], 652);
        for l in 1..7 {
            let ratio = n[l] as f64 / n[l - 1] as f64;
            assert!((ratio - 1.0 / 1.2).abs() < 0.01, "{ratio}");
        }
    }

    #[test]
    fn the_settings_scale_with_the_image() {
        let p = OrbParams::exoter_for_size(512, 384);
        assert_eq!((p.features, p.levels), (750, 8));
        // 96 px: 96 / 1.2^4 = 46.3 ≥ 40 > 96 / 1.2^5 = 38.6.
        let p = OrbParams::exoter_for_size(128, 96);
        assert_eq!(p.levels, 5);
    }
}
