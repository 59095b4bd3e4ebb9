//! Strips of the camera frames around each loss of track, for runs whose
//! VO reads images: per loss, the reference keyframe, the last frame
//! tracked before the loss, the lost frame and the next two processed
//! frames, each the left image with the features the VO found drawn on
//! it. A bar over each panel gives its outcome: blue a keyframe, green
//! tracked, red lost. `plots/losses.md` lists each strip's panels with
//! their times, the gap and the true motion since the reference, and the
//! feature counts.

use std::fmt::Write as _;
use std::path::Path;

use gpodo_frontends::run::ProcessedFrame;
use gpodo_frontends::scheme::SchemeResult;
use gpodo_frontends::traverse::Traverse;
use gpodo_frontends::vo::FrameRef;
use gpodo_frontends::vo::stereo::StereoFrames;
use gpodo_vision::GrayImage;
use gpodo_vision::png_io::write_png_rgb;

/// Strips drawn per scheme and traverse at most (the rest are counted).
pub(crate) const MAX_STRIPS: usize = 5;

/// Pixels between panels, and the height of the outcome bar.
const GAP_PX: usize = 8;
const BAR_PX: usize = 10;

/// Colours: a feature matched in the right image (a map point), one
/// without a match, and the outcome bars.
const MATCHED: [u8; 3] = [40, 230, 40];
const UNMATCHED: [u8; 3] = [240, 60, 40];
const KEYFRAME: [u8; 3] = [40, 110, 250];
const TRACKED: [u8; 3] = [40, 200, 40];
const LOST: [u8; 3] = [230, 30, 30];

/// The positions in `processed` where tracking was lost: a frame not
/// tracked after one that was (or first of all).
pub(crate) fn losses(processed: &[ProcessedFrame]) -> Vec<usize> {
    (0..processed.len())
        .filter(|&k| !processed[k].tracked && (k == 0 || processed[k - 1].tracked))
        .collect()
}

/// The processed frames (positions in `processed`) a strip around the
/// loss at `lost` shows, in order: the last keyframe before it, the last
/// frame before it (when not that keyframe), the lost frame and the next
/// two.
pub(crate) fn panels(processed: &[ProcessedFrame], lost: usize) -> Vec<usize> {
    let mut out = Vec::new();
    let before = lost.checked_sub(1);
    if let Some(keyframe) = (0..lost).rev().find(|&k| processed[k].keyframe) {
        out.push(keyframe);
    }
    if let Some(b) = before
        && out.last() != Some(&b)
    {
        out.push(b);
    }
    out.extend(lost..(lost + 3).min(processed.len()));
    out
}

/// An RGB canvas.
struct Canvas {
    width: usize,
    height: usize,
    rgb: Vec<u8>,
}

impl Canvas {
    fn new(width: usize, height: usize) -> Self {
        Self {
            width,
            height,
            rgb: vec![255; 3 * width * height],
        }
    }

    fn set(&mut self, x: i64, y: i64, colour: [u8; 3]) {
        if x < 0 || y < 0 || x as usize >= self.width || y as usize >= self.height {
            return;
        }
        let k = 3 * (y as usize * self.width + x as usize);
        self.rgb[k..k + 3].copy_from_slice(&colour);
    }

    fn gray(&mut self, image: &GrayImage, x0: usize, y0: usize) {
        for y in 0..image.height() {
            for (x, &p) in image.row(y).iter().enumerate() {
                self.set((x0 + x) as i64, (y0 + y) as i64, [p; 3]);
            }
        }
    }

    fn fill(&mut self, x0: usize, y0: usize, w: usize, h: usize, colour: [u8; 3]) {
        for y in y0..y0 + h {
            for x in x0..x0 + w {
                self.set(x as i64, y as i64, colour);
            }
        }
    }

    /// A square outline of half-side `r` around `(x, y)`.
    fn square(&mut self, x: i64, y: i64, r: i64, colour: [u8; 3]) {
        for d in -r..=r {
            self.set(x + d, y - r, colour);
            self.set(x + d, y + r, colour);
            self.set(x - r, y + d, colour);
            self.set(x + r, y + d, colour);
        }
    }

    /// A cross of half-length `r` at `(x, y)`.
    fn cross(&mut self, x: i64, y: i64, r: i64, colour: [u8; 3]) {
        for d in -r..=r {
            self.set(x + d, y + d, colour);
            self.set(x + d, y - d, colour);
        }
    }
}

/// One panel's facts, for the index.
struct Panel {
    frame: ProcessedFrame,
    keypoints: usize,
    matched: usize,
}

/// Draws the strip of `shown` (positions in `scheme.run.processed`) from
/// `frames` into `path`; returns each panel's facts.
fn draw(
    frames: &StereoFrames,
    scheme: &SchemeResult,
    shown: &[usize],
    path: &Path,
) -> anyhow::Result<Vec<Panel>> {
    let [w, h] = frames.camera().image_size_px.map(|n| n as usize);
    let mut canvas = Canvas::new(shown.len() * (w + GAP_PX) - GAP_PX, h + BAR_PX + 2);
    let mut panels = Vec::new();
    for (slot, &k) in shown.iter().enumerate() {
        let frame = scheme.run.processed[k];
        let at = FrameRef {
            index: frame.frame,
            time_secs: frame.time_secs,
        };
        let (left, _) = frames
            .pair(at)
            .map_err(|e| anyhow::anyhow!("the loss strip of `{}`: {e}", scheme.label))?;
        let x0 = slot * (w + GAP_PX);
        let bar = match (frame.tracked, frame.keyframe) {
            (false, _) => LOST,
            (true, true) => KEYFRAME,
            (true, false) => TRACKED,
        };
        canvas.fill(x0, 0, w, BAR_PX, bar);
        canvas.gray(&left, x0, BAR_PX + 2);
        let features = frames.features(at);
        let (mut keypoints, mut matched) = (0, 0);
        if let Ok(f) = features.as_ref() {
            for (p, right) in f.stereo.left.keypoints.iter().zip(&f.stereo.right_x) {
                let (x, y) = (
                    x0 as i64 + p.x.round() as i64,
                    (BAR_PX + 2) as i64 + p.y.round() as i64,
                );
                if right.is_some() {
                    canvas.square(x, y, 3, MATCHED);
                    matched += 1;
                } else {
                    canvas.cross(x, y, 2, UNMATCHED);
                }
                keypoints += 1;
            }
        }
        panels.push(Panel {
            frame,
            keypoints,
            matched,
        });
    }
    write_png_rgb(path, canvas.width, canvas.height, &canvas.rgb)?;
    Ok(panels)
}

/// Writes a strip PNG per loss of track of `scheme` on `traverse` (the
/// first [`MAX_STRIPS`]) into `dir` as `loss_{file}.{n}.png`, and returns
/// their section of `losses.md` (empty without losses).
///
/// # Errors
/// A frame that cannot be rendered or read again, or an I/O error.
pub(crate) fn write_strips(
    traverse: &Traverse,
    frames: &StereoFrames,
    scheme: &SchemeResult,
    dir: &Path,
    file: &str,
) -> anyhow::Result<String> {
    let processed = &scheme.run.processed;
    let lost = losses(processed);
    if lost.is_empty() {
        return Ok(String::new());
    }
    let mut md = format!(
        "## {} on `{}`: {} losses of track\n\n",
        scheme.label,
        traverse.name(),
        lost.len()
    );
    for (n, &k) in lost.iter().take(MAX_STRIPS).enumerate() {
        let shown = panels(processed, k);
        let name = format!("loss_{file}.{}.png", n + 1);
        let facts = draw(frames, scheme, &shown, &dir.join(&name))?;
        let reference = shown
            .first()
            .map_or(processed[k].time_secs, |&r| processed[r].time_secs);
        let from = traverse.ground_truth_at(reference).inverse();
        let _ = writeln!(
            md,
            "![loss {} at {:.1} s]({name})\n\n| frame | time [s] | gap [s] | since reference: m, deg | outcome | features | stereo-matched |\n|---:|---:|---:|---:|---|---:|---:|",
            n + 1,
            processed[k].time_secs
        );
        for (i, p) in facts.iter().enumerate() {
            let gap = match shown[i].checked_sub(1) {
                Some(prev) => format!("{:.1}", p.frame.time_secs - processed[prev].time_secs),
                None => "–".into(),
            };
            let motion = from * traverse.ground_truth_at(p.frame.time_secs);
            let outcome = match (p.frame.tracked, p.frame.keyframe) {
                (false, _) => "lost",
                (true, true) => "keyframe",
                (true, false) => "tracked",
            };
            let _ = writeln!(
                md,
                "| {} | {:.1} | {gap} | {:.3}, {:.1} | {outcome} | {} | {} |",
                p.frame.frame,
                p.frame.time_secs,
                motion.translation.vector.norm(),
                motion.rotation.angle().to_degrees(),
                p.keypoints,
                p.matched
            );
        }
        md.push('\n');
    }
    if lost.len() > MAX_STRIPS {
        let _ = writeln!(md, "({} more not drawn.)\n", lost.len() - MAX_STRIPS);
    }
    Ok(md)
}

/// The header of `losses.md`.
pub(crate) const INDEX_HEADER: &str = "# Losses of track\n\nThe left camera frames around each loss of track of each scheme: the reference keyframe, the last frame tracked before the loss, the lost frame and the next two processed frames. The bar over a panel is blue for a keyframe, green for a tracked frame, red for a lost one. Green squares are ORB features with a match in the right image (the VO's map points), red crosses features without one. Gaps are to the previous processed frame; the motion is the ground truth's since the reference keyframe.\n\n";

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(frame: usize, keyframe: bool, tracked: bool) -> ProcessedFrame {
        ProcessedFrame {
            frame,
            time_secs: frame as f64 * 0.4,
            distance_m: 0.0,
            keyframe,
            tracked,
            vo_pose: None,
        }
    }

    #[test]
    fn each_loss_is_the_first_untracked_frame_after_a_tracked_one() {
        let processed = [
            frame(0, true, true),
            frame(5, false, true),
            frame(10, false, false),
            frame(15, false, false),
            frame(20, true, true),
            frame(25, false, false),
        ];
        assert_eq!(losses(&processed), vec![2, 5]);
        // Keyframe, last tracked, lost, and the next two.
        assert_eq!(panels(&processed, 2), vec![0, 1, 2, 3, 4]);
        // The last frame before the loss is the keyframe; none after.
        assert_eq!(panels(&processed, 5), vec![4, 5]);
        assert_eq!(losses(&[frame(0, false, false)]), vec![0]);
        assert_eq!(panels(&[frame(0, false, false)], 0), vec![0]);
    }

    #[test]
    fn markers_land_on_their_pixels_and_clip_at_the_edges() {
        let mut canvas = Canvas::new(20, 10);
        canvas.square(5, 5, 2, MATCHED);
        canvas.cross(0, 0, 2, UNMATCHED);
        let at = |c: &Canvas, x: usize, y: usize| {
            let k = 3 * (y * c.width + x);
            [c.rgb[k], c.rgb[k + 1], c.rgb[k + 2]]
        };
        assert_eq!(at(&canvas, 3, 3), MATCHED);
        assert_eq!(at(&canvas, 7, 5), MATCHED);
        assert_eq!(at(&canvas, 5, 5), [255; 3]);
        assert_eq!(at(&canvas, 0, 0), UNMATCHED);
        assert_eq!(at(&canvas, 2, 2), UNMATCHED);
    }
}
