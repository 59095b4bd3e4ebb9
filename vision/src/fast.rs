//! The FAST-9 corner detector (Rosten & Drummond 2006) as OpenCV's
//! `FastFeatureDetector` (`TYPE_9_16`) runs it inside ORB and ORB-SLAM:
//!
//! * a pixel `p` of intensity `I_p` is a corner at threshold `t` when 9
//!   contiguous pixels of the 16 on the Bresenham circle of radius 3 are all
//!   brighter than `I_p + t` or all darker than `I_p − t` (strictly);
//! * its score is the largest threshold at which it would still be one:
//!   `max(t, A, B) − 1`, with `A` (`B`) the largest, over the 16 arcs of 9
//!   contiguous circle pixels, of the arc's smallest `I_p − I_x`
//!   (`I_x − I_p`);
//! * with non-maximum suppression, a corner is kept when its score is
//!   strictly above the scores of its 8 neighbours (0 for a non-corner).
//!
//! Corners are looked for at least 3 pixels from every edge. These are
//! OpenCV's rules to the pixel, so that counts compare with the vision
//! yardstick's one for one (the tests check this on real images).

use crate::{GrayImage, PixelBox};

/// The circle's 16 pixels as `(dx, dy)`, in order around it.
pub const CIRCLE: [(isize, isize); 16] = [
    (0, 3),
    (1, 3),
    (2, 2),
    (3, 1),
    (3, 0),
    (3, -1),
    (2, -2),
    (1, -3),
    (0, -3),
    (-1, -3),
    (-2, -2),
    (-3, -1),
    (-3, 0),
    (-3, 1),
    (-2, 2),
    (-1, 3),
];

/// Contiguous circle pixels a corner needs.
pub const ARC: usize = 9;

/// A detected corner.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Corner {
    /// Column.
    pub x: usize,
    /// Row.
    pub y: usize,
    /// The largest threshold at which it is still a corner.
    pub score: u8,
}

/// `I_p − I_x` around the circle of the pixel at `(x, y)` (at least 3
/// pixels from every edge).
fn differences(image: &GrayImage, x: usize, y: usize) -> [i16; 16] {
    let centre = i16::from(image.get(x, y));
    CIRCLE.map(|(dx, dy)| {
        let (cx, cy) = (x.wrapping_add_signed(dx), y.wrapping_add_signed(dy));
        centre - i16::from(image.get(cx, cy))
    })
}

/// Whether some 9 contiguous entries of the circle all satisfy `test`.
fn has_arc(d: &[i16; 16], test: impl Fn(i16) -> bool) -> bool {
    let mut run = 0;
    // Twice around, so that a run through the start is seen whole.
    for k in 0..16 + ARC - 1 {
        if test(d[k % 16]) {
            run += 1;
            if run >= ARC {
                return true;
            }
        } else {
            run = 0;
        }
    }
    false
}

/// `(A, B)`: over the 16 arcs of 9 contiguous circle pixels, the largest
/// of an arc's smallest `d` (darker side) and of its smallest `−d`
/// (brighter side). Each arc's minimum is built from minima of 2, 4 and 8
/// (64 comparisons a side instead of 144). A pixel is a corner at `t`
/// exactly when `max(A, B) > t`, and its score is `max(A, B) − 1`.
fn arc_extremes(d: &[i16; 16]) -> (i16, i16) {
    let side = |sign: i16| {
        let v: [i16; 16] = std::array::from_fn(|k| sign * d[k]);
        let m2: [i16; 16] = std::array::from_fn(|k| v[k].min(v[(k + 1) % 16]));
        let m4: [i16; 16] = std::array::from_fn(|k| m2[k].min(m2[(k + 2) % 16]));
        let m8: [i16; 16] = std::array::from_fn(|k| m4[k].min(m4[(k + 4) % 16]));
        (0..16)
            .map(|k| m8[k].min(v[(k + 8) % 16]))
            .max()
            .unwrap_or(i16::MIN)
    };
    (side(1), side(-1))
}

/// The score of a corner at `threshold` with circle differences `d`.
fn corner_score(d: &[i16; 16], threshold: u8) -> u8 {
    let mut best = i16::from(threshold);
    for start in 0..16 {
        let arc = (0..ARC).map(|k| d[(start + k) % 16]);
        let darker = arc.clone().min().unwrap_or(0);
        let brighter = arc.map(|v| -v).min().unwrap_or(0);
        best = best.max(darker).max(brighter);
    }
    u8::try_from(best - 1).unwrap_or(u8::MAX)
}

/// The corner score of the pixel at `(x, y)` at `threshold`, or `None`
/// when it is not a corner there (or lies within 3 pixels of an edge).
pub fn score_at(image: &GrayImage, x: usize, y: usize, threshold: u8) -> Option<u8> {
    if x < 3 || y < 3 || x + 3 >= image.width() || y + 3 >= image.height() {
        return None;
    }
    let t = i16::from(threshold);
    // Any 9 contiguous circle pixels hold 2 of the 4 compass pixels (0, 4,
    // 8, 12): without 2 of them on one side there is no corner.
    let centre = i16::from(image.get(x, y));
    let (mut dark, mut bright) = (0, 0);
    for (dx, dy) in [CIRCLE[0], CIRCLE[4], CIRCLE[8], CIRCLE[12]] {
        let v = centre - i16::from(image.get(x.wrapping_add_signed(dx), y.wrapping_add_signed(dy)));
        dark += usize::from(v > t);
        bright += usize::from(v < -t);
    }
    if dark < 2 && bright < 2 {
        return None;
    }
    let d = differences(image, x, y);
    // A dark neighbour has a positive difference.
    let corner = has_arc(&d, |v| v > t) || has_arc(&d, |v| v < -t);
    corner.then(|| corner_score(&d, threshold))
}

/// The FAST-9 corners of `image` at `threshold`, row by row, with
/// non-maximum suppression when `nonmax` (as OpenCV's
/// `FastFeatureDetector`).
pub fn detect(image: &GrayImage, threshold: u8, nonmax: bool) -> Vec<Corner> {
    let width = image.width();
    let scores = score_map(image, threshold);
    let mut found: Vec<Corner> = scores
        .iter()
        .enumerate()
        .filter(|(_, s)| **s > 0)
        .map(|(k, &score)| Corner {
            x: k % width,
            y: k / width,
            score,
        })
        .collect();
    if !nonmax {
        return found;
    }
    found.retain(|c| {
        let at = |x: usize, y: usize| scores[y * width + x];
        (c.y - 1..=c.y + 1)
            .all(|y| (c.x - 1..=c.x + 1).all(|x| (x == c.x && y == c.y) || c.score > at(x, y)))
    });
    found
}

/// The FAST score of every pixel at `threshold`, row-major: the corner's
/// score (at least `threshold`), or 0 where there is no corner. A corner's
/// score does not depend on the threshold it was found at, so one map at
/// the lower of two thresholds answers both: a pixel is a corner at
/// `t ≥ threshold` exactly when its score is at least `t`. The same test
/// as [`score_at`], on the row-major pixels through precomputed offsets.
pub fn score_map(image: &GrayImage, threshold: u8) -> Vec<u8> {
    let (width, height) = (image.width(), image.height());
    let mut scores = vec![0u8; width * height];
    if width < 7 || height < 7 {
        return scores;
    }
    let pixels = image.pixels();
    let offsets = CIRCLE.map(|(dx, dy)| dy * width as isize + dx);
    let t = i16::from(threshold);
    for y in 3..height - 3 {
        for x in 3..width - 3 {
            let idx = y * width + x;
            let centre = i16::from(pixels[idx]);
            let at = |k: usize| i16::from(pixels[idx.wrapping_add_signed(offsets[k])]);
            let (mut dark, mut bright) = (0, 0);
            for k in [0, 4, 8, 12] {
                let v = centre - at(k);
                dark += usize::from(v > t);
                bright += usize::from(v < -t);
            }
            if dark < 2 && bright < 2 {
                continue;
            }
            // 9 contiguous pixels hold 4 of the 8 even ones.
            let (mut dark, mut bright) = (0, 0);
            for k in [0, 2, 4, 6, 8, 10, 12, 14] {
                let v = centre - at(k);
                dark += usize::from(v > t);
                bright += usize::from(v < -t);
            }
            if dark < 4 && bright < 4 {
                continue;
            }
            let d: [i16; 16] = std::array::from_fn(|k| centre - at(k));
            let (a, b) = arc_extremes(&d);
            let best = a.max(b);
            if best > t {
                scores[idx] = u8::try_from(best - 1).unwrap_or(u8::MAX);
            }
        }
    }
    scores
}

/// The corners of `corners` inside `region`.
pub fn count_in(corners: &[Corner], region: &PixelBox) -> usize {
    corners.iter().filter(|c| region.contains(c.x, c.y)).count()
}
