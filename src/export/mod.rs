//! Results for the rest of the tool chain: plots of a run, designs as URDF robots with their
//! SRDF (allowed-collision matrix), reachability paths as joint trajectories keyed by URDF
//! joint names, and the browser report (`view`: one self-contained HTML page in 3D).

pub mod plot;
pub mod srdf;
pub mod trajectory;
pub mod urdf;
pub mod view;

pub use srdf::{design_to_srdf, write_srdf};
pub use urdf::{design_to_urdf, write_urdf};
