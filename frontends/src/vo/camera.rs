//! The camera the visual odometry sees through: [`CameraParams`], defined
//! in `gpodo-traits` so that the simulator's rendered stereo camera reads
//! the same description (its overlap model, pinhole pair and defaults are
//! documented there).

pub use gpodo_traits::camera::{CameraParams, InvalidCameraField};
