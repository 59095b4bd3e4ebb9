//! ORB against closed forms: the intensity centroid of a ramp points up
//! the ramp, and a quarter turn of the image turns every keypoint, its
//! angle and its surroundings with it, so its descriptor stays.

#![allow(clippy::unwrap_used)]

use gpodo_vision::GrayImage;
use gpodo_vision::orb::{OrbParams, centroid_angle, extract, hamming};

/// A textured image: sums of sines at several scales and directions, on a
/// grey ramp.
fn texture(width: usize, height: usize) -> GrayImage {
    let pixels = (0..width * height)
        .map(|k| {
            let (x, y) = ((k % width) as f64, (k / width) as f64);
            let v = 110.0
                + 40.0 * (0.21 * x + 0.05 * y).sin() * (0.17 * y - 0.03 * x).cos()
                + 25.0 * (0.53 * x - 0.41 * y).sin()
                + 20.0 * (0.9 * y + 0.3 * x).cos() * (0.07 * x).sin()
                + 0.1 * x;
            v.round().clamp(0.0, 255.0) as u8
        })
        .collect();
    GrayImage::from_pixels(width, height, pixels).unwrap()
}

#[test]
fn the_centroid_of_a_ramp_points_up_the_ramp() {
    for degrees in [0.0f64, 30.0, 90.0, 135.0, 200.0, -60.0] {
        let theta = degrees.to_radians();
        let (w, h) = (41, 41);
        let pixels = (0..w * h)
            .map(|k| {
                let (u, v) = ((k % w) as f64 - 20.0, (k / w) as f64 - 20.0);
                (128.0 + 3.0 * (u * theta.cos() + v * theta.sin())).round() as u8
            })
            .collect();
        let image = GrayImage::from_pixels(w, h, pixels).unwrap();
        let angle = f64::from(centroid_angle(&image, 20, 20));
        let diff = (angle - theta + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
            - std::f64::consts::PI;
        // Rounding the ramp to grey levels moves the centroid a little.
        assert!(
            diff.abs() < 0.5f64.to_radians(),
            "{degrees}°: {}",
            angle.to_degrees()
        );
    }
}

/// The image turned a quarter turn clockwise on screen: the pixel at
/// `(x, y)` goes to `(h − 1 − y, x)`.
fn quarter_turn(image: &GrayImage) -> GrayImage {
    let (w, h) = (image.width(), image.height());
    let mut out = GrayImage::filled(h, w, 0);
    for y in 0..h {
        for x in 0..w {
            out.set(h - 1 - y, x, image.get(x, y));
        }
    }
    out
}

#[test]
fn a_quarter_turn_turns_the_keypoints_and_keeps_their_descriptors() {
    let image = texture(240, 240);
    let params = OrbParams {
        features: 300,
        levels: 1,
        ..OrbParams::exoter()
    };
    let before = extract(&image, &params).unwrap();
    let after = extract(&quarter_turn(&image), &params).unwrap();
    assert!(before.keypoints.len() > 100, "{}", before.keypoints.len());
    let mut matched = 0;
    let mut distances = Vec::new();
    for (k, p) in before.keypoints.iter().enumerate() {
        let (x, y) = (239.0 - p.y, p.x);
        let Some(q) = after
            .keypoints
            .iter()
            .position(|q| (q.x - x).abs() < 0.5 && (q.y - y).abs() < 0.5)
        else {
            continue;
        };
        matched += 1;
        let turn = f64::from(after.keypoints[q].angle - p.angle);
        let turn = (turn - std::f64::consts::FRAC_PI_2).rem_euclid(std::f64::consts::TAU);
        let off = turn.min(std::f64::consts::TAU - turn);
        assert!(off < 1e-3, "keypoint {k}: turned by {}", turn.to_degrees());
        distances.push(hamming(&before.descriptors[k], &after.descriptors[q]));
    }
    // The quadtree's cells do not turn with the image, so not every
    // keypoint is kept by both; most are.
    assert!(
        matched * 2 > before.keypoints.len(),
        "{matched} of {}",
        before.keypoints.len()
    );
    distances.sort_unstable();
    let median = distances[distances.len() / 2];
    // Unrelated descriptors differ in about 128 of 256 bits.
    assert!(
        median <= 2,
        "median Hamming distance {median}: {distances:?}"
    );
}

#[test]
fn a_full_image_gets_its_budget_over_the_levels() {
    let image = texture(512, 384);
    let params = OrbParams::exoter_for_size(512, 384);
    let features = extract(&image, &params).unwrap();
    assert_eq!(features.keypoints.len(), features.descriptors.len());
    assert!(features.keypoints.len() <= params.features);
    assert!(features.keypoints.len() > params.features / 2);
    // Every level has some, each keypoint inside the image.
    for l in 0..params.levels as u8 {
        assert!(features.keypoints.iter().any(|k| k.level == l), "level {l}");
    }
    for k in &features.keypoints {
        assert!(k.x >= 19.0 && k.y >= 19.0 && k.x < 512.0 - 19.0 && k.y < 384.0 - 19.0);
    }
    // The same image gives the same features.
    assert_eq!(extract(&image, &params).unwrap(), features);
}
