//! The world the robot works in: obstacles, tasks (points, with an optional orientation or approach cone) and clearance (paper §II-B).

pub mod convert;
pub mod mesh;
pub mod obstacle;
pub mod task;
pub mod workspace;

pub use obstacle::{MeshCache, MeshRepresentation, Obstacle, ObstacleShape};
pub use task::TaskOrientation;
pub use workspace::{Contact, Workspace};
