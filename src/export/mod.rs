//! Results for the rest of the tool chain: plots of a run.

pub mod plot;
