//! Designs and the design space (paper §III-B, Eq. 18–22).

#[allow(clippy::module_inception)]
pub mod design;
pub mod space;

pub use design::{AxisRanges, Design, LinkDesign};
pub use space::{DesignSpace, Param, Variable};
