//! The robot's environment: obstacle geometry.

pub mod mesh;
