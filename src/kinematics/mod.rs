//! The generic parametric serial chain (paper §II-A): links with fixed geometry and six-axis
//! actuation, and allocation-free forward kinematics.

pub mod axis;
pub mod chain;
pub mod link;
pub mod placement;
pub mod trig;

pub use axis::{Axis, Range};
pub use chain::{step_length, ArcLayout, Chain, Frames, FreeAxis};
pub use link::{Dh, Link, LinkGeometry};
pub use placement::Placement;
