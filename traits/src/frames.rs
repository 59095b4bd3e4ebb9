//! The camera's frames as the stereo VO reads them: a frame of the camera
//! stream ([`FrameRef`]) and where its rectified grey pair comes from
//! ([`StereoFrameSource`]): the rendered testbed camera (`gpodo-testbed`)
//! or a recording's image topics (`gpodo-datasets`), behind one seam so
//! that neither the tracker nor the sources know of each other.

use gpodo_vision::GrayImage;
use serde::{Deserialize, Serialize};

/// A camera frame: its index in the traverse's camera stream and its time.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct FrameRef {
    /// Index in the camera stream.
    pub index: usize,
    /// Time stamp (s).
    pub time_secs: f64,
}

/// Where the stereo VO gets its images: the rendered camera, or a
/// recording's image topics.
///
/// ```
/// use gpodo_traits::{FrameRef, StereoFrameSource};
/// use gpodo_vision::GrayImage;
///
/// /// Two flat grey images for every frame.
/// struct Flat;
///
/// impl StereoFrameSource for Flat {
///     fn pair(&self, frame: FrameRef) -> Result<(GrayImage, GrayImage), String> {
///         let image = GrayImage::from_pixels(8, 6, vec![128; 48])
///             .map_err(|e| format!("frame {}: {e}", frame.index))?;
///         Ok((image.clone(), image))
///     }
/// }
///
/// let (left, _) = Flat.pair(FrameRef { index: 0, time_secs: 0.0 }).unwrap();
/// assert_eq!(left.width(), 8);
/// ```
pub trait StereoFrameSource: Send + Sync {
    /// The rectified grey pair (left, right) of `frame`.
    ///
    /// # Errors
    /// A message naming the frame and what could not be had.
    fn pair(&self, frame: FrameRef) -> Result<(GrayImage, GrayImage), String>;
}
