//! A camera's stereo frames for the stereo VO: where the images come from
//! ([`StereoFrameSource`]) and each frame's features, computed once and
//! shared by every VO that holds the same [`StereoFrames`].

use std::collections::HashMap;
use std::sync::{Arc, Mutex};

use gpodo_vision::GrayImage;
use gpodo_vision::orb::OrbParams;
use gpodo_vision::stereo::{StereoFeatures, stereo_features};

use crate::vo::{CameraParams, FrameRef};

/// Where the stereo VO gets its images: the rendered camera, or a
/// recording's image topics.
pub trait StereoFrameSource: Send + Sync {
    /// The rectified grey pair (left, right) of `frame`.
    ///
    /// # Errors
    /// A message naming the frame and what could not be had.
    fn pair(&self, frame: FrameRef) -> Result<(GrayImage, GrayImage), String>;
}

/// A frame's features, computed once.
pub(super) type Cached = Arc<Result<StereoFeatures, String>>;

/// A camera's frames and their features, each computed once and shared by
/// every VO (every scheme of a run) that holds this in an [`Arc`].
pub struct StereoFrames {
    camera: CameraParams,
    orb: OrbParams,
    source: Arc<dyn StereoFrameSource>,
    cache: Mutex<HashMap<usize, Cached>>,
}

impl StereoFrames {
    /// The frames of `source`, seen by `camera`, their ORB settings
    /// ExoTeR's for the camera's image size.
    pub fn new(camera: CameraParams, source: Arc<dyn StereoFrameSource>) -> Self {
        let [w, h] = camera.image_size_px.map(|n| n as usize);
        Self {
            orb: OrbParams::exoter_for_size(w, h),
            camera,
            source,
            cache: Mutex::new(HashMap::new()),
        }
    }

    /// The camera.
    pub fn camera(&self) -> &CameraParams {
        &self.camera
    }

    /// The features of `frame`, from the cache or computed (and cached).
    pub fn features(&self, frame: FrameRef) -> Cached {
        if let Some(hit) = self.lock().get(&frame.index) {
            return Arc::clone(hit);
        }
        let computed = self.source.pair(frame).and_then(|(left, right)| {
            stereo_features(&left, &right, &self.orb, self.camera.focal_px)
                .map_err(|e| format!("frame {}: {e}", frame.index))
        });
        let entry = Arc::new(computed);
        self.lock().insert(frame.index, Arc::clone(&entry));
        entry
    }

    /// How many frames' features are cached.
    pub fn cached(&self) -> usize {
        self.lock().len()
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, HashMap<usize, Cached>> {
        // A poisoned cache only means a panic elsewhere; its entries are
        // whole.
        self.cache.lock().unwrap_or_else(|e| e.into_inner())
    }
}
