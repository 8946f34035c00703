//! Schedules for the planner as an optimisation progresses (paper §V): a step bound `L_max` that
//! starts coarse and shrinks, and an RRT iteration budget that grows.

use serde::{Deserialize, Serialize};

/// Start and end values of `L_max` and of the iteration budget; in between, `L_max` follows a
/// geometric interpolation (equal ratios per unit of progress) and the budget a linear one.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Schedule {
    /// `[start, end]` of `L_max` (radians-and-metres, as the metric of paper Eq. 10).
    #[serde(deserialize_with = "crate::limits::exact::array")]
    pub l_max: [f64; 2],
    /// `[start, end]` of the RRT iteration budget.
    #[serde(deserialize_with = "crate::limits::exact::array")]
    pub iterations: [usize; 2],
}

impl Schedule {
    /// `L_max` at `progress` ∈ [0, 1] (clamped): `start·(end/start)^progress`.
    pub fn l_max_at(&self, progress: f64) -> f64 {
        let p = progress.clamp(0.0, 1.0);
        let [a, b] = self.l_max;
        a * (b / a).powf(p)
    }

    /// The iteration budget at `progress` ∈ [0, 1] (clamped), rounded to the nearest integer.
    pub fn iterations_at(&self, progress: f64) -> usize {
        let p = progress.clamp(0.0, 1.0);
        let [a, b] = self.iterations;
        (a as f64 + (b as f64 - a as f64) * p).round() as usize
    }

    /// Checks that both `L_max` values are positive and finite and both budgets at least 1;
    /// the error names the field below `planner.schedule`.
    pub fn validate(&self) -> crate::Result<()> {
        use crate::limits::{within, MAX_ITERATIONS, MAX_SETTING};
        if !self
            .l_max
            .iter()
            .all(|&v| v > 0.0 && within(v, MAX_SETTING))
        {
            return Err(crate::Error::invalid(
                "planner.schedule.l_max",
                format!("{:?}", self.l_max),
                format!("both values must be positive and at most {MAX_SETTING}"),
            ));
        }
        if !self
            .iterations
            .iter()
            .all(|n| (1..=MAX_ITERATIONS).contains(n))
        {
            return Err(crate::Error::invalid(
                "planner.schedule.iterations",
                format!("{:?}", self.iterations),
                format!("both values must lie in 1..={MAX_ITERATIONS}"),
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn coarse_to_fine_and_growing() {
        let s = Schedule {
            l_max: [0.8, 0.2],
            iterations: [500, 2500],
        };
        assert!((s.l_max_at(0.0) - 0.8).abs() < 1e-15);
        assert!((s.l_max_at(1.0) - 0.2).abs() < 1e-15);
        assert!(
            (s.l_max_at(0.5) - 0.4).abs() < 1e-12,
            "geometric mean halfway"
        );
        assert!((s.l_max_at(7.0) - 0.2).abs() < 1e-15, "progress is clamped");
        assert_eq!(s.iterations_at(0.0), 500);
        assert_eq!(s.iterations_at(0.5), 1500);
        assert_eq!(s.iterations_at(1.0), 2500);
        let mut prev = f64::INFINITY;
        for i in 0..=10 {
            let l = s.l_max_at(i as f64 / 10.0);
            assert!(l < prev);
            prev = l;
        }
        assert!(Schedule {
            l_max: [0.0, 1.0],
            iterations: [1, 1]
        }
        .validate()
        .is_err());
    }
}
