//! Input from other tools: existing serial robots from URDF files, as kinsynth chains.

pub mod body;
pub mod urdf;

pub use body::{load_robot, BodyChoice, BodyKind, ImportOptions, ImportedRobot};
pub use urdf::{chain_from_urdf, load_chain, UrdfChain};
