//! The rendered camera as the stereo VO's frame source: each camera frame
//! rendered from the rover's true pose at its time, with the exposure's
//! motion blur, through the testbed's ground maps. The poses come from
//! whoever builds the frames (a traverse's ground truth, a scripted
//! drive); the frames know nothing of where they came from.

use std::sync::Arc;

use gpodo_traits::{CameraParams, FrameRef, StereoFrameSource};
use gpodo_vision::GrayImage;
use nalgebra::Isometry3;

use super::{GroundMaps, SensorSpec, StereoRenderer};

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

    /// The true `world_from_camera` of each frame's left camera, indexed
    /// as the camera stream: for controls that see ground truth, handed to
    /// the tracker by whoever builds it.
    pub fn true_camera_poses(&self) -> Vec<Isometry3<f64>> {
        self.poses
            .iter()
            .map(|pose| pose.world_from_body * self.camera.body_from_camera())
            .collect()
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
}
