//! The rendered camera as the stereo VO's frame source: each camera frame
//! of a traverse rendered from the rover's true pose at its time, with
//! the exposure's motion blur, through the testbed's ground maps.

use std::sync::Arc;

use gpodo_datasets::camera::{GroundMaps, SensorSpec, StereoRenderer};
use gpodo_frontends::traverse::Traverse;
use gpodo_frontends::vo::FrameRef;
use gpodo_frontends::vo::stereo::StereoFrameSource;
use gpodo_traits::CameraParams;
use gpodo_vision::GrayImage;
use nalgebra::Isometry3;

/// One frame's true pose and its exposure's motion.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FramePose {
    /// `world_from_body` at the middle of the exposure.
    pub world_from_body: Isometry3<f64>,
    /// `body_start_from_body_end` over the exposure.
    pub exposure_motion: Isometry3<f64>,
}

/// Frames rendered on demand (see the module).
pub struct RenderedFrames {
    ground: Arc<GroundMaps>,
    camera: CameraParams,
    sensor: SensorSpec,
    seed: u64,
    poses: Vec<FramePose>,
}

impl RenderedFrames {
    /// The frames at `poses` (indexed as the traverse's camera stream) of
    /// `ground` through `camera`, their noise drawn from `seed`.
    pub fn new(
        ground: Arc<GroundMaps>,
        camera: CameraParams,
        sensor: SensorSpec,
        seed: u64,
        poses: Vec<FramePose>,
    ) -> Self {
        Self {
            ground,
            camera,
            sensor,
            seed,
            poses,
        }
    }
}

impl RenderedFrames {
    /// The frames of `traverse`'s camera stream: each at the traverse's
    /// ground truth at the frame's time, blurred by the motion over
    /// `camera`'s exposure centred there.
    pub fn from_traverse(
        ground: Arc<GroundMaps>,
        camera: CameraParams,
        sensor: SensorSpec,
        seed: u64,
        traverse: &Traverse,
    ) -> Self {
        let half = 0.5 * camera.exposure_secs;
        let poses = traverse
            .camera_times_secs()
            .iter()
            .map(|&t| FramePose {
                world_from_body: traverse.ground_truth_at(t),
                exposure_motion: traverse.ground_truth_at(t - half).inverse()
                    * traverse.ground_truth_at(t + half),
            })
            .collect();
        Self::new(ground, camera, sensor, seed, poses)
    }
}

impl StereoFrameSource for RenderedFrames {
    fn pair(&self, frame: FrameRef) -> Result<(GrayImage, GrayImage), String> {
        let pose = self.poses.get(frame.index).ok_or_else(|| {
            format!(
                "frame {}: the rendered camera has {} frames",
                frame.index,
                self.poses.len()
            )
        })?;
        let renderer = StereoRenderer::new(self.camera, &self.ground, self.sensor, self.seed)
            .map_err(|e| format!("frame {}: {e}", frame.index))?;
        let pair = renderer.render(
            &pose.world_from_body,
            &pose.exposure_motion,
            frame.index as u64,
        );
        Ok((pair.left, pair.right))
    }

    fn true_camera_pose(&self, frame: FrameRef) -> Option<Isometry3<f64>> {
        let pose = self.poses.get(frame.index)?;
        Some(pose.world_from_body * self.camera.body_from_camera())
    }
}
