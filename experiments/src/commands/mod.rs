//! The commands beside `gpodo run`, as library functions the binary, the
//! Python package and the tests call: a preset's testbed written out
//! ([`simulate`]), recordings imported through a topic map ([`import`]),
//! gpodo on the robot ([`live`]) with its frame gate built from a gate
//! file ([`gate`]), and the statistical tracker set beside
//! the stereo VO on rendered drives ([`tracker_calibration`]).

pub mod gate;
pub mod import;
pub mod keyframe_chain;
pub mod live;
pub mod live_gate;
pub mod replay_frontend;
pub mod simulate;
pub mod tracker_calibration;
