//! Key poses: what a rig looks like between its keys.
//!
//! * [`pose_at`] and [`posed_at`]: the pose at a time, interpolated between the rig
//!   file's keys ([`project::Animation::keys`]) linearly or smoothly, with holds.
//! * [`SpatialBlend`]: spatial keyframing (Igarashi, Moscovich and Hughes 2005,
//!   §5.3): key poses placed at markers on the canvas, blended at a control cursor by
//!   radial basis functions.
//! * [`simplify`]: a recorded performance (one pose a frame) brought down to the few
//!   keys that reproduce it within a tolerance.
//! * [`frame_times`]: the frames of an export.
//!
//! Every pose is read through its *channels* (`channels.rs`): a point handle's
//! translation, rotation and scale as keyed; a bar's centre, direction and length
//! (the direction unwrapped from key to key by the smaller turn, so a bar turns
//! rigidly); each cage vertex's position. Interpolating or blending a pose is doing so
//! to each channel. No method, picture or UI is known here.

mod channels;
mod record;
mod spatial;
mod time;

pub use record::{DEFAULT_TOLERANCE, resample, simplify};
pub use spatial::SpatialBlend;
pub use time::{frame_count, frame_times, pose_at, posed_at};
