//! FAST-9 against closed forms (the segment test's strict threshold, the
//! score as the largest threshold that keeps a corner, a square's four
//! corners and no edge) and, on the real ground images of `../shared/`,
//! against OpenCV's `FastFeatureDetector` corner for corner.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::{Path, PathBuf};

use gpodo_vision::fast::{CIRCLE, detect, score_at};
use gpodo_vision::png_io::{read_png_gray, write_png_gray};
use gpodo_vision::{GrayImage, VisionError};

/// A 15 × 15 image of `background` whose centre's circle pixels `arc`
/// (indices into [`CIRCLE`]) are `value`.
fn circle_image(background: u8, value: u8, arc: impl IntoIterator<Item = usize>) -> GrayImage {
    let mut image = GrayImage::filled(15, 15, background);
    for k in arc {
        let (dx, dy) = CIRCLE[k];
        image.set(
            7usize.wrapping_add_signed(dx),
            7usize.wrapping_add_signed(dy),
            value,
        );
    }
    image
}

#[test]
fn the_segment_test_is_strict_and_the_score_is_the_largest_threshold_that_keeps_the_corner() {
    // Nine contiguous circle pixels 30 above the centre, wrapping through
    // the start of the circle: a corner below threshold 30, not at 30.
    let image = circle_image(100, 130, (12..16).chain(0..5));
    assert_eq!(score_at(&image, 7, 7, 20), Some(29));
    assert_eq!(score_at(&image, 7, 7, 29), Some(29));
    assert_eq!(score_at(&image, 7, 7, 30), None);
    // Eight are not enough, whatever the contrast.
    let eight = circle_image(100, 250, 0..8);
    assert_eq!(score_at(&eight, 7, 7, 5), None);
    // Darker works the same way; the weakest pixel of the best arc decides.
    let mut dark = circle_image(100, 40, 3..12);
    dark.set(7 + 3, 7, 70); // CIRCLE[4] = (3, 0): 30 below the centre.
    assert_eq!(score_at(&dark, 7, 7, 7), Some(29));
    // No corner within 3 pixels of an edge.
    assert_eq!(score_at(&image, 2, 7, 7), None);
}

#[test]
fn a_bright_square_has_corners_only_at_its_corners_and_ties_are_suppressed() {
    let mut image = GrayImage::filled(60, 60, 50);
    for y in 20..40 {
        for x in 20..40 {
            image.set(x, y, 200);
        }
    }
    let corners = detect(&image, 20, false);
    let square = [(20, 20), (39, 20), (20, 39), (39, 39)];
    let near = |c: &gpodo_vision::fast::Corner, (x, y): (usize, usize)| {
        c.x.abs_diff(x) <= 2 && c.y.abs_diff(y) <= 2
    };
    for corner in &square {
        assert!(
            corners.iter().any(|c| near(c, *corner)),
            "no corner at {corner:?} in {corners:?}"
        );
    }
    // None on the straight edges: a circle there sees at most 7 pixels
    // across the edge.
    assert!(
        corners.iter().all(|c| square.iter().any(|&s| near(c, s))),
        "{corners:?}"
    );
    // Every corner of an ideal square has a neighbour of the same score,
    // and a kept corner must beat all eight (as OpenCV's suppression).
    assert!(detect(&image, 20, true).is_empty());
    // A uniform image has none.
    assert!(detect(&GrayImage::filled(40, 30, 90), 7, false).is_empty());
}

#[test]
fn a_png_round_trips_and_a_bad_file_is_named() {
    let tmp = tempfile::tempdir().unwrap();
    let pixels: Vec<u8> = (0..35u32).map(|v| (v * 7 % 256) as u8).collect();
    let image = GrayImage::from_pixels(7, 5, pixels).unwrap();
    let path = tmp.path().join("round.png");
    write_png_gray(&path, &image).unwrap();
    assert_eq!(read_png_gray(&path).unwrap(), image);

    let bad = tmp.path().join("bad.png");
    std::fs::write(&bad, b"not a png").unwrap();
    let err = read_png_gray(&bad).unwrap_err();
    assert!(matches!(err, VisionError::Png { .. }), "{err}");
    assert!(err.to_string().contains("bad.png"), "{err}");
    assert!(matches!(
        read_png_gray(&tmp.path().join("none.png")),
        Err(VisionError::Io { .. })
    ));
    assert!(GrayImage::from_pixels(3, 3, vec![0; 8]).is_err());
}

/// The real ground images (`../shared/data/images/`).
fn real_images() -> Vec<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/data/images");
    let mut files: Vec<PathBuf> = ["exoter-prl", "curiosity-navcam"]
        .iter()
        .flat_map(|dir| std::fs::read_dir(root.join(dir)).unwrap())
        .map(|entry| entry.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "png"))
        .collect();
    files.sort();
    files
}

/// The Python with OpenCV, or `None` after saying why (a failure in CI).
fn python_with_opencv() -> Option<String> {
    gpodo_testkit::python_with(&["cv2"], "OpenCV (opencv-python-headless)")
}

/// OpenCV's FAST-9 corners of `path` at `threshold`, with non-maximum
/// suppression, as sorted `(x, y, score)`.
fn opencv_corners(python: &str, path: &Path, threshold: u8) -> Vec<(usize, usize, u8)> {
    let script = "import sys, cv2\n\
        image = cv2.imread(sys.argv[1], cv2.IMREAD_GRAYSCALE)\n\
        fast = cv2.FastFeatureDetector_create(threshold=int(sys.argv[2]), nonmaxSuppression=True)\n\
        for k in fast.detect(image, None):\n\
        \x20   print(int(k.pt[0]), int(k.pt[1]), int(k.response))\n";
    let threshold = threshold.to_string();
    let text = gpodo_testkit::run_python(python, script, &[path.as_os_str(), threshold.as_ref()]);
    let mut corners: Vec<(usize, usize, u8)> = text
        .lines()
        .map(|line| {
            let v: Vec<usize> = line.split(' ').map(|f| f.parse().unwrap()).collect();
            (v[0], v[1], u8::try_from(v[2]).unwrap())
        })
        .collect();
    corners.sort_unstable();
    corners
}

#[test]
fn on_real_ground_images_the_corners_are_opencvs_one_for_one() {
    let Some(python) = python_with_opencv() else {
        return;
    };
    let images = real_images();
    assert_eq!(images.len(), 6, "{images:?}");
    for path in images {
        let image = read_png_gray(&path).unwrap();
        for threshold in [20, 7] {
            let mut ours: Vec<(usize, usize, u8)> = detect(&image, threshold, true)
                .iter()
                .map(|c| (c.x, c.y, c.score))
                .collect();
            ours.sort_unstable();
            let theirs = opencv_corners(&python, &path, threshold);
            assert!(!theirs.is_empty(), "{}", path.display());
            assert_eq!(
                ours.len(),
                theirs.len(),
                "{} at threshold {threshold}",
                path.display()
            );
            assert!(
                ours == theirs,
                "{} at threshold {threshold}",
                path.display()
            );
        }
    }
}
