//! Writes a rendered stereo sequence for a peer VO, with gpodo's stereo VO
//! run on it: the same drive as the stereo VO's accuracy test (compact
//! soil on a flat 9 × 9 m patch, 0.03 m/s turning at 0.01 rad/s, ExoTeR's
//! mast camera at 512 × 384, 2.5 fps), and the same wheel-odometry-like
//! prior (5 % short, 0.2° off in yaw).
//!
//! ```text
//! cargo run --release -p gpodo-experiments --example stereo_sequence -- OUT [FRAMES [FEATURES MIN_THRESHOLD]]
//! ```
//!
//! `FEATURES` and `MIN_THRESHOLD` set the VO's `features` and
//! `fast_min_threshold` (default ExoTeR's: 750 at 512 × 384, and 7).
//!
//! `OUT` gets `left/NNNNNN.png`, `right/NNNNNN.png`, `calibration.json`
//! (the rectified camera and the ORB settings) and `pairs.csv`: per
//! (gap, first frame) the truth, the prior and gpodo's estimate (empty
//! when lost) of the left camera's motion `reference_from_current`
//! (translation in metres, then the quaternion x, y, z, w), and gpodo's
//! time for that pair (features of the current frame, both images, plus
//! tracking, in seconds on one thread; the reference's features cached),
//! its inliers and the reference's map points.
//! `bench/peers/stereo_vo_opencv.py` reads the folder.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::fmt::Write as _;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use gpodo_frontends::vo::stereo::{StereoFrames, StereoVo, StereoVoParams};
use gpodo_frontends::vo::{FrameRef, TrackOutcome, TrackPurpose, TrackRequest, VisualOdometry};
use gpodo_testbed::camera::{FramePose, RenderedFrames};
use gpodo_testbed::camera::{GroundMaps, SceneSpec, SensorSpec};
use gpodo_testbed::sim::soil::{Soil, SoilMap};
use gpodo_testbed::sim::terrain::Terrain;
use gpodo_traits::CameraParams;
use gpodo_traits::StereoFrameSource;
use gpodo_vision::GrayImage;
use gpodo_vision::png_io::write_png_gray;
use nalgebra::{Isometry3, Translation3, UnitQuaternion};

const FPS: f64 = 2.5;
const GAPS: [usize; 3] = [1, 5, 12];

fn drive(frames: usize) -> Vec<FramePose> {
    let (speed, turn) = (0.03, 0.01);
    (0..frames)
        .map(|k| {
            let t = k as f64 / FPS;
            let yaw = turn * t;
            FramePose {
                world_from_body: Isometry3::from_parts(
                    Translation3::new(
                        1.5 + speed / turn * yaw.sin(),
                        3.0 + speed / turn * (1.0 - yaw.cos()),
                        0.25,
                    ),
                    UnitQuaternion::from_euler_angles(0.0, 0.0, yaw),
                ),
                exposure_motion: Isometry3::identity(),
            }
        })
        .collect()
}

fn frame(k: usize) -> FrameRef {
    FrameRef {
        index: k,
        time_secs: k as f64 / FPS,
    }
}

/// The pairs rendered once, so that no clock counts rendering.
struct Rendered(Vec<(GrayImage, GrayImage)>);

impl StereoFrameSource for Rendered {
    fn pair(&self, frame: FrameRef) -> Result<(GrayImage, GrayImage), String> {
        self.0
            .get(frame.index)
            .cloned()
            .ok_or_else(|| format!("no frame {}", frame.index))
    }
}

fn pose_fields(p: &Isometry3<f64>) -> String {
    let t = p.translation.vector;
    let q = p.rotation.coords;
    format!(
        "{:.9},{:.9},{:.9},{:.12},{:.12},{:.12},{:.12}",
        t.x, t.y, t.z, q.x, q.y, q.z, q.w
    )
}

fn main() -> anyhow::Result<()> {
    let mut args = std::env::args().skip(1);
    let out = PathBuf::from(
        args.next()
            .ok_or_else(|| anyhow::anyhow!("usage: OUT [FRAMES]"))?,
    );
    let frames: usize = args.next().map_or(Ok(220), |a| a.parse())?;
    let mut params = StereoVoParams::default();
    if let (Some(features), Some(threshold)) = (args.next(), args.next()) {
        params.features = Some(features.parse()?);
        params.fast_min_threshold = threshold.parse()?;
    }
    let poses = drive(frames);
    let ground = GroundMaps::build(
        &Terrain::flat(9.0)?,
        &SoilMap::uniform(Soil::compact(), 9.0)?,
        &SceneSpec::default(),
        11,
    )?;
    let camera = CameraParams::exoter_bumblebee2().scaled(0.5);
    let renderer = Arc::new(RenderedFrames::new(
        Arc::new(ground),
        camera,
        SensorSpec::default(),
        11,
        poses.clone(),
    ));
    std::fs::create_dir_all(out.join("left"))?;
    std::fs::create_dir_all(out.join("right"))?;
    let mut pairs = Vec::with_capacity(frames);
    for k in 0..frames {
        let (left, right) = renderer.pair(frame(k)).map_err(anyhow::Error::msg)?;
        write_png_gray(&out.join(format!("left/{k:06}.png")), &left)?;
        write_png_gray(&out.join(format!("right/{k:06}.png")), &right)?;
        pairs.push((left, right));
    }
    let source = Arc::new(Rendered(pairs));
    let [w, h] = camera.image_size_px;
    let orb = params.orb(&camera);
    let [cx, cy] = camera.principal_point();
    let calibration = serde_json::json!({
        "width": w, "height": h,
        "focal_px": camera.focal_px, "cx": cx, "cy": cy,
        "baseline_m": camera.baseline_m,
        "fps": FPS,
        "orb": {
            "features": orb.features, "scale_factor": orb.scale_factor,
            "levels": orb.levels, "ini_threshold": orb.ini_threshold,
            "min_threshold": orb.min_threshold,
        },
        "vo": serde_json::to_value(&params)?,
    });
    std::fs::write(
        out.join("calibration.json"),
        serde_json::to_string_pretty(&calibration)?,
    )?;

    let b = camera.body_from_camera();
    let in_camera = |body: &Isometry3<f64>| b.inverse() * body * b;
    let mut csv = String::from(
        "gap,first,truth_tx,truth_ty,truth_tz,truth_qx,truth_qy,truth_qz,truth_qw,\
         prior_tx,prior_ty,prior_tz,prior_qx,prior_qy,prior_qz,prior_qw,\
         gpodo_tx,gpodo_ty,gpodo_tz,gpodo_qx,gpodo_qy,gpodo_qz,gpodo_qw,gpodo_secs,gpodo_inliers,gpodo_map_points\n",
    );
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build()?;
    pool.install(|| -> anyhow::Result<()> {
        for gap in GAPS {
            for k in 0..frames.saturating_sub(gap) {
                // A fresh cache per pair, the reference's features made
                // before the clock starts: the time is one processed frame.
                let frames_cache = Arc::new(StereoFrames::with_orb(camera, source.clone(), orb));
                let mut vo = StereoVo::new(params.clone(), frames_cache)?;
                let _ = vo.features(frame(k));
                let truth = poses[k].world_from_body.inverse() * poses[k + gap].world_from_body;
                let prior = Isometry3::from_parts(
                    Translation3::from(truth.translation.vector * 0.95),
                    truth.rotation * UnitQuaternion::from_euler_angles(0.0, 0.0, 0.0035),
                );
                let started = Instant::now();
                let outcome = vo.track(&TrackRequest {
                    reference: frame(k),
                    current: frame(k + gap),
                    prior: Some(prior),
                    purpose: TrackPurpose::Tracking,
                });
                let secs = started.elapsed().as_secs_f64();
                let map_points = vo.map_point_count(frame(k));
                let (estimate, inliers) = match outcome {
                    TrackOutcome::Tracked(m) => (
                        pose_fields(&in_camera(&m.relative)),
                        vo.tracked_inliers(frame(k + gap)).unwrap_or(0),
                    ),
                    TrackOutcome::Lost => (",,,,,,".into(), 0),
                };
                writeln!(
                    csv,
                    "{gap},{k},{},{},{estimate},{secs:.6},{inliers},{map_points}",
                    pose_fields(&in_camera(&truth)),
                    pose_fields(&in_camera(&prior)),
                )?;
            }
        }
        Ok(())
    })?;
    std::fs::write(out.join("pairs.csv"), csv)?;
    println!("wrote {frames} pairs and pairs.csv to {}", out.display());
    Ok(())
}
