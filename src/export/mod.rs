//! Results for the rest of the tool chain: plots of a run, designs as URDF robots, and
//! reachability paths as joint trajectories keyed by URDF joint names.

pub mod plot;
pub mod trajectory;
pub mod urdf;

pub use urdf::{design_to_urdf, write_urdf};
