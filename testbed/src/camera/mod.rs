//! The rendered stereo camera of the simulated testbed: a rectified 8-bit
//! grey pair (and a depth buffer for tests) from the rover's true pose,
//! CPU only, through one [`gpodo_traits::CameraParams`].
//!
//! * **Geometry** ([`ground`]): the simulator's height field (hills and
//!   slopes), each soil's micro-relief, and stones (pebbles and rocks)
//!   scattered per soil from the seed's own stream. Beyond the 9 × 9 m
//!   area the camera sees the lab's floor, flat at height 0 and
//!   untextured; a ray that meets nothing within 30 m sees the dark hall.
//! * **Appearance** ([`look`]): a multi-scale seeded albedo texture per
//!   soil; a key light plus ambient with cast shadows; the sensor's shot
//!   and read noise and 8-bit quantisation; motion blur over the exposure
//!   from the true motion ([`render`]).
//! * **Determinism**: every value is a function of the seed, the pose and
//!   the frame's index; images are the same bytes at any thread count.
//!
//! The camera is off unless asked for: nothing here draws from the
//! simulator's streams, and the wheels roll on the simulator's terrain
//! alone (the stones are seen, not felt).

mod blur;
pub mod calibration;
mod convert;
pub mod frames;
pub mod ground;
pub mod look;
mod max_mips;
mod noise;
pub mod render;
mod tiled;
pub mod traverse;

pub use frames::{FramePose, RenderedFrames};
pub use ground::GroundMaps;
pub use look::{Lighting, SceneSpec, SoilLook, StoneSize};
pub use render::{SensorSpec, StereoFrame, StereoRenderer};
