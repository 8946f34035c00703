#![doc = include_str!("../README.md")]
#![warn(missing_docs)]

pub mod collision;
pub mod design;
pub mod error;
pub mod export;
pub mod import;
pub mod io;
pub mod kinematics;
pub mod limits;
pub mod optimize;
pub mod planning;
pub mod scenario;
pub mod strict;
pub mod world;

pub use design::{Design, DesignSpace};
pub use error::{Error, Result};
pub use kinematics::{Axis, Chain, Frames, Range};
pub use scenario::Scenario;
pub use world::{Obstacle, Workspace};
