//! A camera's stereo frames for the stereo VO: the images of a
//! [`StereoFrameSource`] and each frame's features, computed once and
//! shared by every VO that holds the same [`StereoFrames`]; and, for the
//! controls that see ground truth, the true camera poses that whoever
//! built the frames handed down with them.

use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

use gpodo_traits::StereoFrameSource;
use gpodo_vision::GrayImage;
use gpodo_vision::orb::OrbParams;
use gpodo_vision::stereo::{StereoFeatures, stereo_features};
use nalgebra::Isometry3;

use crate::vo::{CameraParams, FrameRef};

/// What a frame gives the VO, computed once: its stereo features and a
/// whole-image signature for place recognition.
pub struct FrameFeatures {
    /// ORB features of the left image and their right matches.
    pub stereo: StereoFeatures,
    /// The left image averaged over a 32 × 24 grid of blocks, less its
    /// mean, scaled to unit length (a "tiny image": two frames of one
    /// place correlate, whatever their features).
    pub signature: Vec<f32>,
}

/// A frame's features, computed once.
pub(super) type Cached = Arc<Result<FrameFeatures, String>>;

/// The signature of [`FrameFeatures::signature`].
fn signature(image: &GrayImage) -> Vec<f32> {
    let (w, h) = (image.width(), image.height());
    let (columns, rows) = (32, 24);
    let mut sums = vec![0f64; columns * rows];
    let mut counts = vec![0u32; columns * rows];
    for y in 0..h {
        let j = y * rows / h;
        for (x, &p) in image.row(y).iter().enumerate() {
            let k = j * columns + x * columns / w;
            sums[k] += f64::from(p);
            counts[k] += 1;
        }
    }
    let means: Vec<f64> = sums
        .iter()
        .zip(&counts)
        .map(|(s, &c)| s / f64::from(c.max(1)))
        .collect();
    let mean = means.iter().sum::<f64>() / means.len() as f64;
    let norm = means.iter().map(|m| (m - mean).powi(2)).sum::<f64>().sqrt();
    means
        .iter()
        .map(|m| {
            if norm > 0.0 {
                ((m - mean) / norm) as f32
            } else {
                0.0
            }
        })
        .collect()
}

/// A camera's frames and their features, each computed once and shared by
/// every VO (every scheme of a run) that holds this in an [`Arc`].
pub struct StereoFrames {
    camera: CameraParams,
    orb: OrbParams,
    source: Arc<dyn StereoFrameSource>,
    /// The true `world_from_camera` of each frame's left camera, indexed
    /// as the camera stream, when the builder knows them (a rendered
    /// camera does, a recording does not).
    true_camera_poses: Option<Vec<Isometry3<f64>>>,
    /// One slot per frame asked for: the first asker computes it, and
    /// every other (another scheme's thread) waits for that result.
    cache: Mutex<HashMap<usize, Arc<OnceLock<Cached>>>>,
}

impl StereoFrames {
    /// The frames of `source`, seen by `camera`, their ORB settings
    /// ExoTeR's for the camera's image size.
    pub fn new(camera: CameraParams, source: Arc<dyn StereoFrameSource>) -> Self {
        let [w, h] = camera.image_size_px.map(|n| n as usize);
        Self::with_orb(camera, source, OrbParams::exoter_for_size(w, h))
    }

    /// The frames of `source`, seen by `camera`, with the ORB settings
    /// `orb` (see [`super::StereoVoParams::orb`]).
    pub fn with_orb(
        camera: CameraParams,
        source: Arc<dyn StereoFrameSource>,
        orb: OrbParams,
    ) -> Self {
        Self {
            orb,
            camera,
            source,
            true_camera_poses: None,
            cache: Mutex::new(HashMap::new()),
        }
    }

    /// These frames with the true `world_from_camera` of each frame's left
    /// camera (indexed as the camera stream): for controls that see ground
    /// truth (`LocalMapPlacement::GroundTruth`), never for tracking.
    pub fn with_true_camera_poses(self, poses: Vec<Isometry3<f64>>) -> Self {
        Self {
            true_camera_poses: Some(poses),
            ..self
        }
    }

    /// The camera.
    pub fn camera(&self) -> &CameraParams {
        &self.camera
    }

    /// The true `world_from_camera` of `frame`'s left camera, if it was
    /// handed down ([`Self::with_true_camera_poses`]).
    pub fn true_camera_pose(&self, frame: FrameRef) -> Option<Isometry3<f64>> {
        self.true_camera_poses.as_ref()?.get(frame.index).copied()
    }

    /// The features of `frame`, from the cache or computed (and cached):
    /// each frame's are computed once, however many threads ask at once.
    pub fn features(&self, frame: FrameRef) -> Cached {
        let slot = Arc::clone(self.lock().entry(frame.index).or_default());
        Arc::clone(slot.get_or_init(|| Arc::new(self.compute(frame))))
    }

    /// Renders or reads `frame`'s pair and finds its features.
    fn compute(&self, frame: FrameRef) -> Result<FrameFeatures, String> {
        let computed = self.source.pair(frame).and_then(|(left, right)| {
            let stereo = stereo_features(&left, &right, &self.orb, self.camera.focal_px)
                .map_err(|e| format!("frame {}: {e}", frame.index))?;
            Ok(FrameFeatures {
                stereo,
                signature: signature(&left),
            })
        });
        if let Err(e) = &computed {
            tracing::warn!("stereo VO: no features for {e}; frames that need it are lost");
        }
        computed
    }

    /// The rectified pair of `frame`, rendered or read again (images are
    /// not cached; their features are).
    ///
    /// # Errors
    /// The source's message naming the frame.
    pub fn pair(&self, frame: FrameRef) -> Result<(GrayImage, GrayImage), String> {
        self.source.pair(frame)
    }

    /// How many frames' features are cached.
    pub fn cached(&self) -> usize {
        self.lock()
            .values()
            .filter(|slot| slot.get().is_some())
            .count()
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, HashMap<usize, Arc<OnceLock<Cached>>>> {
        // A poisoned cache only means a panic elsewhere; its entries are
        // whole.
        self.cache.lock().unwrap_or_else(|e| e.into_inner())
    }
}
