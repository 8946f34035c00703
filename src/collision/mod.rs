//! Collision checking of the robot body against the workspace: closed-form distances, the
//! scene with its broad phase, body models, the four edge checkers and the dense-sampling
//! oracle.

pub mod body;
pub mod distance;
pub mod edge;
pub mod hull;
pub mod oracle;
pub mod scene;

pub use body::{BodyModel, RobotBody, SelfCollisionConfig};
pub use edge::{make_checker, CheckerKind, EdgeChecker, EdgeStats, Scratch};
pub use scene::CollisionScene;
