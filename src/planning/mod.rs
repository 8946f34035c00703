//! Motion planning for reachability: the goal-biased RRT in actuation space (paper §II-D),
//! damped-least-squares IK steps, the reachability ratio (Eq. 11–12) and the `L_max` and
//! iteration schedules (§V).

pub mod config;
pub mod feasible;
pub mod ik;
pub mod reach;
pub mod rrt;
pub mod schedule;

pub use config::PlannerConfig;
pub use reach::{
    reachability, reachability_tasks, reachability_until, PathReport, ReachReport, TargetReport,
};
pub use schedule::Schedule;
