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

use pulp::{Arch, Simd, WithSimd};

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

/// `(A, B)`: over the 16 arcs of 9 contiguous circle pixels, the largest
/// of an arc's smallest `d` (darker side) and of its smallest `−d`
/// (brighter side). Each arc's minimum is built from minima of 2, 4 and 8
/// (64 comparisons a side instead of 144). A pixel is a corner at `t`
/// exactly when `max(A, B) > t`, and its score is `max(A, B) − 1`.
#[inline(always)]
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

/// The score of the pixel at `idx` of the row-major `pixels` at
/// `threshold` (0 for no corner), its circle at `offsets` from it. Any 9
/// contiguous circle pixels hold 2 of the 4 compass pixels and 4 of the 8
/// even ones: without those on one side there is no corner.
#[inline(always)]
fn pixel_score(pixels: &[u8], idx: usize, offsets: &[isize; 16], threshold: u8) -> u8 {
    let t = i16::from(threshold);
    let centre = i16::from(pixels[idx]);
    // A dark neighbour has a positive difference.
    let at = |k: usize| centre - i16::from(pixels[idx.wrapping_add_signed(offsets[k])]);
    for (picks, needed) in [
        (&[0, 4, 8, 12][..], 2),
        (&[0, 2, 4, 6, 8, 10, 12, 14][..], 4),
    ] {
        let (mut dark, mut bright) = (0, 0);
        for &k in picks {
            let v = at(k);
            dark += usize::from(v > t);
            bright += usize::from(v < -t);
        }
        if dark < needed && bright < needed {
            return 0;
        }
    }
    let d: [i16; 16] = std::array::from_fn(at);
    let (a, b) = arc_extremes(&d);
    let best = a.max(b);
    if best > t {
        u8::try_from(best - 1).unwrap_or(u8::MAX)
    } else {
        0
    }
}

/// The circle's offsets in the row-major pixels of an image `width` wide.
fn circle_offsets(width: usize) -> [isize; 16] {
    CIRCLE.map(|(dx, dy)| dy * width as isize + dx)
}

/// The corner score of the pixel at `(x, y)` at `threshold`, or `None`
/// when it is not a corner there (or lies within 3 pixels of an edge).
pub fn score_at(image: &GrayImage, x: usize, y: usize, threshold: u8) -> Option<u8> {
    if x < 3 || y < 3 || x + 3 >= image.width() || y + 3 >= image.height() {
        return None;
    }
    let offsets = circle_offsets(image.width());
    let score = pixel_score(image.pixels(), y * image.width() + x, &offsets, threshold);
    (score > 0).then_some(score)
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
/// `t ≥ threshold` exactly when its score is at least `t`.
pub fn score_map(image: &GrayImage, threshold: u8) -> Vec<u8> {
    Arch::new().dispatch(ScoreMap { image, threshold })
}

/// [`score_map`] on the processor's widest vectors.
struct ScoreMap<'a> {
    image: &'a GrayImage,
    threshold: u8,
}

impl WithSimd for ScoreMap<'_> {
    type Output = Vec<u8>;

    #[inline(always)]
    fn with_simd<S: Simd>(self, _: S) -> Vec<u8> {
        score_map_here(self.image, self.threshold)
    }
}

/// [`score_map`], inlined into its caller's target features.
#[inline(always)]
fn score_map_here(image: &GrayImage, threshold: u8) -> Vec<u8> {
    let (width, height) = (image.width(), image.height());
    let mut scores = vec![0u8; width * height];
    if width < 7 || height < 7 {
        return scores;
    }
    let (pixels, offsets) = (image.pixels(), circle_offsets(width));
    let t = i16::from(threshold);
    let inner = width - 6;
    let mut candidate = vec![false; inner];
    for y in 3..height - 3 {
        // The compass test of `pixel_score` for the whole row first, in a
        // loop the compiler vectorises; the rest only where it passes.
        let shifted = |dy: isize, dx: isize| -> &[u8] {
            let start = (y as isize + dy) * width as isize + dx + 3;
            &pixels[start as usize..start as usize + inner]
        };
        let (centre, north, south, east, west) = (
            shifted(0, 0),
            shifted(-3, 0),
            shifted(3, 0),
            shifted(0, 3),
            shifted(0, -3),
        );
        for (x, pass) in candidate.iter_mut().enumerate() {
            let c = i16::from(centre[x]);
            let (mut dark, mut bright) = (0u8, 0u8);
            for p in [north[x], south[x], east[x], west[x]] {
                let v = c - i16::from(p);
                dark += u8::from(v > t);
                bright += u8::from(v < -t);
            }
            *pass = dark >= 2 || bright >= 2;
        }
        for (x, _) in candidate.iter().enumerate().filter(|(_, pass)| **pass) {
            let idx = y * width + x + 3;
            scores[idx] = pixel_score(pixels, idx, &offsets, threshold);
        }
    }
    scores
}

/// The corners of `corners` inside `region`.
pub fn count_in(corners: &[Corner], region: &PixelBox) -> usize {
    corners.iter().filter(|c| region.contains(c.x, c.y)).count()
}
