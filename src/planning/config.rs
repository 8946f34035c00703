//! Planner settings (the `[planner]` section of a scenario).

use super::schedule::Schedule;
use crate::collision::{BodyModel, CheckerKind, SelfCollisionConfig};
use serde::{Deserialize, Serialize};

/// The `[planner]` section: the RRT that decides reachability (paper §II-D, Eq. 10).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PlannerConfig {
    /// Edge checker. Default `certified`, the only one whose "free" is a proof.
    pub checker: CheckerKind,
    /// Body model used by the `discrete` and `segment` checkers: `capsules` (the real body) or
    /// `points` (the paper's point colliders). Default `capsules`.
    pub body: BodyModel,
    /// Step bound `L_max` of paper Eq. 10 on `‖Δf‖ + λ‖Δa‖`. Default π/4 (paper §IV).
    pub l_max: f64,
    /// Weight `λ` of the actuation-space step in the metric of Eq. 10. Default 0.1.
    pub lambda: f64,
    /// Distance (metres) at which the end effector counts as on a task point. Default 0.02.
    pub goal_tolerance: f64,
    /// RRT iterations per design. Default 2000.
    pub max_iterations: usize,
    /// Probability of growing toward a task point instead of a random sample. Default 0.2.
    pub goal_bias: f64,
    /// Optional wall-clock cap (seconds) per reachability evaluation. Default: none. A time
    /// cap makes results depend on the machine's speed; leave it out for reproducible runs.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub time_limit: Option<f64>,
    /// Damped-least-squares steps per goal-biased extension. Default 20.
    pub ik_steps: usize,
    /// How `l_max` and `max_iterations` change as an optimisation progresses (paper §V).
    /// Default: constant.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub schedule: Option<Schedule>,
    /// Self-collision settings, from the scenario's `[robot]` section (not a `[planner]` key).
    #[serde(skip)]
    pub self_collision: SelfCollisionConfig,
}

impl Default for PlannerConfig {
    fn default() -> Self {
        PlannerConfig {
            checker: CheckerKind::Certified,
            body: BodyModel::Capsules,
            l_max: std::f64::consts::FRAC_PI_4,
            lambda: 0.1,
            goal_tolerance: 0.02,
            max_iterations: 2000,
            goal_bias: 0.2,
            time_limit: None,
            ik_steps: 20,
            schedule: None,
            self_collision: SelfCollisionConfig::default(),
        }
    }
}
