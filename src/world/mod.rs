//! The world the robot works in: obstacles, task points and clearance (paper §II-B).

pub mod convert;
pub mod mesh;
pub mod obstacle;
pub mod workspace;

pub use obstacle::{MeshRepresentation, Obstacle, ObstacleShape};
pub use workspace::{Contact, Workspace};
