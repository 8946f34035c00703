//! Planner settings (the `[planner]` section of a scenario).

use super::schedule::Schedule;
use crate::collision::{BodyModel, CheckerKind, SelfCollisionConfig};
use crate::limits::{
    within, MAX_BUDGET_GROWTH, MAX_IK_STEPS, MAX_ITERATIONS, MAX_LENGTH, MAX_POSTURES, MAX_SETTING,
};
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
    /// Metres per radian between position and orientation errors in the inverse kinematics of
    /// oriented tasks ([`crate::planning::ik::dls_oriented`]): the stacked error is
    /// `[Δp; w·Δθ]`. Default [`DEFAULT_ORIENTATION_WEIGHT`] (1 rad counts as 0.1 m). Unused by
    /// point tasks.
    #[serde(skip_serializing_if = "is_default_orientation_weight")]
    pub orientation_weight: f64,
    /// RRT iterations per design: the budget of a run, unless it grows (see `budget_growth`).
    /// Default 2000.
    pub max_iterations: usize,
    /// Probability of growing toward a task point instead of a random sample. Default 0.2.
    pub goal_bias: f64,
    /// Optional wall-clock cap (seconds) per reachability evaluation. Default: none. A time
    /// cap makes results depend on the machine's speed; leave it out for reproducible runs.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub time_limit: Option<f64>,
    /// Damped-least-squares steps per goal-biased extension. Default 20.
    pub ik_steps: usize,
    /// Backward trees per unreached task: each grows from a collision-free inverse-kinematics
    /// posture that reaches the task until it joins the tree from home. 0 plans with the tree
    /// from home alone. Default 1.
    pub postures: usize,
    /// Hold still, in the inverse kinematics, an axis at a limit of its range that a step
    /// pushes further out, and solve the step again without it ([`crate::planning::ik::dls`]):
    /// the other axes make up for it within the step and the error falls quadratically.
    /// `false` clamps the whole step into the ranges, as the paper's planner does, which cuts
    /// every step short once an axis saturates. Default true (the paper's baseline, `optimize
    /// --baseline` and `experiment`, plans with `false`). Always written out, so that a record
    /// of the settings replays the same plans whatever the default.
    pub ik_hold_limits: bool,
    /// Aim each steering try by the metric's growth per unit of actuation-space distance seen
    /// in the try before (the first by the previous steering), re-aiming a first try that
    /// lands below [`crate::planning::rrt::STEER_SHORT`]` × L_max` once: most steps then take
    /// one or two kinematics evaluations instead of about three. `false` tries the whole step
    /// first. Default false (it changes the plans, and so the optimiser's results).
    #[serde(skip_serializing_if = "is_false")]
    pub aimed_steering: bool,
    /// How far the iteration budget grows: while an unreached task has a backward tree (a
    /// collision-free posture on it is known), a run may use up to `budget_growth ×
    /// max_iterations` iterations (at most [`crate::limits::iteration_cap`] of the design's
    /// axes and `ik_steps`); otherwise it stops at
    /// `max_iterations`. 1 keeps the budget fixed. Default 5.
    pub budget_growth: usize,
    /// How `l_max` and `max_iterations` change as an optimisation progresses (paper §V).
    /// Default: constant.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub schedule: Option<Schedule>,
    /// Self-collision settings, from the scenario's `[robot]` section (not a `[planner]` key).
    #[serde(skip)]
    pub self_collision: SelfCollisionConfig,
}

/// Default [`PlannerConfig::orientation_weight`] (metres per radian).
pub const DEFAULT_ORIENTATION_WEIGHT: f64 = 0.1;

fn is_false(b: &bool) -> bool {
    !*b
}

fn is_default_orientation_weight(w: &f64) -> bool {
    *w == DEFAULT_ORIENTATION_WEIGHT
}

impl PlannerConfig {
    /// Checks every setting; errors name the field below `planner` and its value. Bounds:
    /// [`crate::limits`] (`max_iterations` and the schedule's budgets at most
    /// [`MAX_ITERATIONS`], `ik_steps` at most [`MAX_IK_STEPS`], `postures` at most
    /// [`MAX_POSTURES`], `budget_growth` in 1..=[`MAX_BUDGET_GROWTH`], `goal_tolerance` at most
    /// [`MAX_LENGTH`], `l_max` and `lambda` at most [`MAX_SETTING`]).
    pub fn validate(&self) -> crate::Result<()> {
        let bad = |field: &str, value: &dyn std::fmt::Display, why: String| {
            Err(crate::Error::invalid(
                format!("planner.{field}"),
                value,
                why,
            ))
        };
        if !(self.l_max > 0.0 && within(self.l_max, MAX_SETTING)) {
            return bad(
                "l_max",
                &crate::error::Num(self.l_max),
                format!("must be positive and at most {MAX_SETTING}"),
            );
        }
        if !(self.lambda >= 0.0 && within(self.lambda, MAX_SETTING)) {
            return bad(
                "lambda",
                &crate::error::Num(self.lambda),
                format!("must be finite, not negative and at most {MAX_SETTING}"),
            );
        }
        if !(self.goal_tolerance > 0.0 && within(self.goal_tolerance, MAX_LENGTH)) {
            return bad(
                "goal_tolerance",
                &crate::error::Num(self.goal_tolerance),
                format!("must be positive and at most {MAX_LENGTH} m"),
            );
        }
        if !(self.orientation_weight > 0.0 && within(self.orientation_weight, MAX_SETTING)) {
            return bad(
                "orientation_weight",
                &crate::error::Num(self.orientation_weight),
                format!("must be positive and at most {MAX_SETTING} (metres per radian)"),
            );
        }
        if !(1..=MAX_ITERATIONS).contains(&self.max_iterations) {
            return bad(
                "max_iterations",
                &self.max_iterations,
                format!("must lie in 1..={MAX_ITERATIONS}"),
            );
        }
        if !(0.0..=1.0).contains(&self.goal_bias) {
            return bad("goal_bias", &self.goal_bias, "must lie in [0, 1]".into());
        }
        if let Some(t) = self.time_limit {
            if !(t.is_finite() && t > 0.0) {
                return bad(
                    "time_limit",
                    &crate::error::Num(t),
                    "must be positive and finite".into(),
                );
            }
        }
        if self.ik_steps > MAX_IK_STEPS {
            return bad(
                "ik_steps",
                &self.ik_steps,
                format!("must be at most {MAX_IK_STEPS}"),
            );
        }
        if self.postures > MAX_POSTURES {
            return bad(
                "postures",
                &self.postures,
                format!("must be at most {MAX_POSTURES}"),
            );
        }
        if !(1..=MAX_BUDGET_GROWTH).contains(&self.budget_growth) {
            return bad(
                "budget_growth",
                &self.budget_growth,
                format!("must lie in 1..={MAX_BUDGET_GROWTH}"),
            );
        }
        if let Some(s) = &self.schedule {
            s.validate()?;
        }
        Ok(())
    }
}

impl Default for PlannerConfig {
    fn default() -> Self {
        PlannerConfig {
            checker: CheckerKind::Certified,
            body: BodyModel::Capsules,
            l_max: std::f64::consts::FRAC_PI_4,
            lambda: 0.1,
            goal_tolerance: 0.02,
            orientation_weight: DEFAULT_ORIENTATION_WEIGHT,
            max_iterations: 2000,
            goal_bias: 0.2,
            time_limit: None,
            ik_steps: 20,
            postures: 1,
            ik_hold_limits: true,
            aimed_steering: false,
            budget_growth: 5,
            schedule: None,
            self_collision: SelfCollisionConfig::default(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn postures_and_budget_growth_are_bounded() {
        assert!(PlannerConfig::default().validate().is_ok());
        let with = |postures: usize, budget_growth: usize| PlannerConfig {
            postures,
            budget_growth,
            ..PlannerConfig::default()
        };
        assert!(with(0, 1).validate().is_ok());
        assert!(with(MAX_POSTURES, MAX_BUDGET_GROWTH).validate().is_ok());
        for (config, field) in [
            (with(MAX_POSTURES + 1, 5), "planner.postures"),
            (with(1, 0), "planner.budget_growth"),
            (with(1, MAX_BUDGET_GROWTH + 1), "planner.budget_growth"),
        ] {
            let e = config.validate().unwrap_err().to_string();
            assert!(e.contains(field), "{e}");
        }
    }

    /// The holding inverse kinematics is the default, and a record of settings that clamp
    /// (a `best.json`'s `planner`) reads back as clamping: the key is always written.
    #[test]
    fn ik_hold_limits_defaults_on_and_a_written_false_reads_back_false() {
        assert!(PlannerConfig::default().ik_hold_limits);
        let clamp = PlannerConfig {
            ik_hold_limits: false,
            ..PlannerConfig::default()
        };
        let json = serde_json::to_string(&clamp).unwrap();
        assert!(json.contains("\"ik_hold_limits\":false"), "{json}");
        let back: PlannerConfig = serde_json::from_str(&json).unwrap();
        assert_eq!(back, clamp);
        let toml = toml::to_string(&clamp).unwrap();
        let back: PlannerConfig = toml::from_str(&toml).unwrap();
        assert!(!back.ik_hold_limits, "{toml}");
    }

    #[test]
    fn a_planner_table_without_the_new_keys_takes_their_defaults() {
        let p: PlannerConfig = toml::from_str("max_iterations = 500").unwrap();
        assert_eq!(p.max_iterations, 500);
        assert_eq!(p.postures, 1);
        assert_eq!(p.budget_growth, 5);
        let p: PlannerConfig = toml::from_str("postures = 3\nbudget_growth = 2").unwrap();
        assert_eq!((p.postures, p.budget_growth), (3, 2));
    }
}
