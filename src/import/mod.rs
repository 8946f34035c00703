//! Input from other tools: existing serial robots from URDF files, as kinsynth chains.

pub mod urdf;

pub use urdf::{chain_from_urdf, load_chain, UrdfChain};
