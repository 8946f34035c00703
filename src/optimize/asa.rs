//! Adaptive simulated annealing (Ingber 1989, 1996) with re-annealing, in a batch form that
//! evaluates in parallel.
//!
//! Each axis `i` has its own generating temperature `T_i = T_0·exp(−c·k_i^{1/D})` (`D` the
//! dimension, `k_i` its annealing time) and a candidate moves it by
//! `y = sgn(u − ½)·T_i·((1 + 1/T_i)^{|2u−1|} − 1)` times the axis's range (Ingber's fat-tailed
//! generating distribution), resampled until it falls within the bounds. Acceptance uses the
//! Metropolis rule with its own temperature `T_a = T_a0·exp(−c·k_a^{1/D})`. The rate `c` is set so
//! that the temperatures fall by `temperature_ratio` over `expected_evaluations` (Ingber's
//! quenching, tuned to the budget).
//!
//! Batch form: a step draws `batch` candidates around the current point, evaluates them in
//! parallel, then applies the acceptance rule to them in order. Re-annealing: every
//! `reanneal_interval` acceptances, the cost's sensitivity `s_i` along each axis is estimated at
//! the best point by finite differences (`D` more evaluations, in parallel), each `T_i` is
//! stretched by `s_max/s_i` (insensitive axes search wider) with `k_i` reset to match, and the
//! acceptance temperature restarts from the best cost's scale.

use super::{
    best_distinct, check_evaluated, check_len, check_points, keep_best, random_point, Cut,
    Evaluated, Optimizer, StateSpace, StepContext, StepReport,
};
use crate::error::Num;
use crate::limits::{MAX_POPULATION, MAX_SETTING};
use crate::scenario::{check, check_count, check_positive_within};
use rand::RngExt;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

/// ASA settings (`[optimizer.asa]`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct AsaParams {
    /// Candidates per step, evaluated in parallel. Default 16.
    pub batch: usize,
    /// Initial generating temperature `T_0` (as a fraction of each range). Default 1.
    pub initial_temperature: f64,
    /// Factor by which the temperatures fall over `expected_evaluations`. Default 1e-6.
    pub temperature_ratio: f64,
    /// Evaluations over which the schedule runs. Default 20000.
    pub expected_evaluations: u64,
    /// Acceptances between re-annealings. Default 100.
    pub reanneal_interval: u64,
}

impl Default for AsaParams {
    fn default() -> Self {
        AsaParams {
            batch: 16,
            initial_temperature: 1.0,
            temperature_ratio: 1e-6,
            expected_evaluations: 20_000,
            reanneal_interval: 100,
        }
    }
}

impl AsaParams {
    /// Checks the settings, with field names under `prefix`: a scenario's `[optimizer.asa]`
    /// (`optimizer.asa.`) and a checkpoint's state read back (`params.`) obey the same rules.
    pub fn check(&self, prefix: &str) -> crate::Result<()> {
        let field = |name: &str| format!("{prefix}{name}");
        check_count(self.batch, 1, MAX_POPULATION, field("batch"))?;
        let t = self.initial_temperature;
        check_positive_within(t, MAX_SETTING, "", field("initial_temperature"))?;
        let r = self.temperature_ratio;
        check(
            r > 0.0 && r <= 1.0,
            field("temperature_ratio"),
            r,
            "must lie in (0, 1]",
        )?;
        for (n, name) in [
            (self.expected_evaluations, "expected_evaluations"),
            (self.reanneal_interval, "reanneal_interval"),
        ] {
            check(n > 0, field(name), n, "must be at least 1")?;
        }
        Ok(())
    }
}

/// The annealer's state.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Asa {
    params: AsaParams,
    seeds: Vec<Vec<f64>>,
    current: Option<Evaluated>,
    best: Option<Evaluated>,
    /// Per-axis annealing times and initial temperatures.
    k: Vec<f64>,
    t0: Vec<f64>,
    /// Acceptance annealing time and initial temperature.
    k_accept: f64,
    t0_accept: f64,
    accepted: u64,
    since_reanneal: u64,
}

impl Asa {
    /// An annealer starting from the first of `seeds` (or a random point).
    pub fn new(params: AsaParams, seeds: Vec<Vec<f64>>) -> Self {
        Asa {
            params,
            seeds,
            current: None,
            best: None,
            k: Vec::new(),
            t0: Vec::new(),
            k_accept: 0.0,
            t0_accept: 1.0,
            accepted: 0,
            since_reanneal: 0,
        }
    }

    /// Restores an annealer from [`Optimizer::save`] output.
    pub fn load(state: serde_json::Value) -> serde_json::Result<Self> {
        crate::strict::deserialize(state).map_err(serde_path_to_error::Error::into_inner)
    }

    /// The rate `c` that brings a temperature down by `temperature_ratio` at
    /// `expected_evaluations`, for dimension `d`.
    fn rate(&self, d: usize) -> f64 {
        let k_end = (self.params.expected_evaluations.max(2)) as f64;
        -self.params.temperature_ratio.ln() / k_end.powf(1.0 / d.max(1) as f64)
    }

    fn temperature(&self, t0: f64, k: f64, d: usize) -> f64 {
        t0 * (-self.rate(d) * k.max(0.0).powf(1.0 / d.max(1) as f64)).exp()
    }

    fn generate(&self, x: &[f64], lower: &[f64], upper: &[f64], rng: &mut ChaCha8Rng) -> Vec<f64> {
        let d = x.len();
        (0..d)
            .map(|i| {
                let range = upper[i] - lower[i];
                if range <= 0.0 {
                    return x[i];
                }
                let t = self.temperature(self.t0[i], self.k[i], d).max(1e-300);
                for _ in 0..100 {
                    let u: f64 = rng.random();
                    let y = (u - 0.5).signum()
                        * t
                        * ((1.0 + 1.0 / t).powf((2.0 * u - 1.0).abs()) - 1.0);
                    let v = x[i] + y * range;
                    if v >= lower[i] && v <= upper[i] {
                        return v;
                    }
                }
                x[i]
            })
            .collect()
    }
}

impl Optimizer for Asa {
    fn name(&self) -> &'static str {
        "asa"
    }

    fn step(&mut self, ctx: StepContext<'_>) -> StepReport {
        let (lower, upper) = (ctx.problem.lower(), ctx.problem.upper());
        let d = lower.len();
        let batch = ctx.batch();
        let rng = ctx.rng;
        let Some(current) = self.current.clone() else {
            // First step: the start point plus a batch of random points, whose cost spread sets
            // the initial acceptance temperature.
            let mut xs: Vec<Vec<f64>> = self.seeds.iter().take(1).cloned().collect();
            while xs.len() < self.params.batch.max(2) {
                xs.push(random_point(lower, upper, rng));
            }
            let n = xs.len() as u64;
            let ev = match batch.evaluate(xs) {
                Ok(v) => v,
                Err(cut) => return StepReport::cut(cut),
            };
            let mean = ev.iter().map(|e| e.cost).sum::<f64>() / ev.len() as f64;
            let var = ev.iter().map(|e| (e.cost - mean).powi(2)).sum::<f64>() / ev.len() as f64;
            self.t0_accept = var.sqrt().max(1e-9);
            self.k = vec![0.0; d];
            self.t0 = vec![self.params.initial_temperature; d];
            for e in &ev {
                keep_best(&mut self.best, e);
            }
            self.current = Some(ev[0].clone());
            return StepReport::done(n);
        };
        let xs: Vec<Vec<f64>> = (0..self.params.batch.max(1))
            .map(|_| self.generate(&current.x, lower, upper, rng))
            .collect();
        let mut evaluations = xs.len() as u64;
        let ev = match batch.evaluate(xs) {
            Ok(v) => v,
            Err(cut) => return StepReport::cut(cut),
        };
        let mut cur = current;
        // Kept for the result should the probes below be cut short.
        let taken = ev.clone();
        for e in ev {
            keep_best(&mut self.best, &e);
            let t_accept = self
                .temperature(self.t0_accept, self.k_accept, d)
                .max(1e-300);
            let delta = e.cost - cur.cost;
            let u: f64 = rng.random();
            if delta <= 0.0 || u < (-delta / t_accept).exp() {
                cur = e;
                self.accepted += 1;
                self.since_reanneal += 1;
            }
            self.k_accept += 1.0;
            for k in &mut self.k {
                *k += 1.0;
            }
        }
        self.current = Some(cur);
        if self.since_reanneal >= self.params.reanneal_interval {
            self.since_reanneal = 0;
            let best = self
                .best
                .clone()
                .expect("a best point after the first step");
            let probes: Vec<Vec<f64>> = (0..d)
                .map(|i| {
                    let mut x = best.x.clone();
                    let h = 1e-3 * (upper[i] - lower[i]);
                    x[i] = if x[i] + h <= upper[i] {
                        x[i] + h
                    } else {
                        x[i] - h
                    };
                    x
                })
                .collect();
            let probing = batch.after(evaluations);
            evaluations += probes.len() as u64;
            let ev = match probing.evaluate(probes) {
                Ok(v) => v,
                Err(cut) => {
                    let mut evaluated = taken;
                    evaluated.extend(cut.evaluated);
                    return StepReport::cut(Cut { evaluated });
                }
            };
            let s: Vec<f64> = ev
                .iter()
                .enumerate()
                .map(|(i, e)| {
                    keep_best(&mut self.best, e);
                    let h = (e.x[i] - best.x[i]).abs().max(1e-300);
                    ((e.cost - best.cost) / h).abs()
                })
                .collect();
            let s_max = s.iter().copied().fold(0.0, f64::max);
            if s_max > 0.0 {
                let c = self.rate(d);
                let new_k: Vec<f64> = s
                    .iter()
                    .zip(self.t0.iter().zip(&self.k))
                    .map(|(&si, (&t0, &k))| {
                        let t = self.temperature(t0, k, d);
                        let t_new = (t * s_max / si.max(s_max * 1e-6)).min(t0);
                        ((t0 / t_new).ln() / c).max(0.0).powf(d as f64)
                    })
                    .collect();
                self.k = new_k;
            }
            // Acceptance: restart from the scale of the best cost, keeping the current time.
            let t_now = self.temperature(self.t0_accept, self.k_accept, d);
            self.t0_accept = self.t0_accept.min(best.cost.abs().max(1e-9)).max(t_now);
            let c = self.rate(d);
            self.k_accept = ((self.t0_accept / t_now.max(1e-300)).ln() / c)
                .max(0.0)
                .powf(d as f64);
        }
        StepReport::done(evaluations)
    }

    fn best(&self) -> Option<&Evaluated> {
        self.best.as_ref()
    }

    fn snapshot(&self) -> Box<dyn Optimizer> {
        Box::new(self.clone())
    }

    fn save(&self) -> serde_json::Value {
        serde_json::to_value(self).expect("ASA state serialises")
    }

    fn candidates(&self) -> Vec<&Evaluated> {
        self.current.iter().chain(self.best.as_ref()).collect()
    }

    fn emigrants(&self, count: usize) -> Vec<Evaluated> {
        best_distinct(self.current.iter().chain(self.best.as_ref()), count)
    }

    fn immigrate(&mut self, migrants: &[Evaluated]) {
        let Some(first) = best_distinct(migrants, 1).into_iter().next() else {
            return;
        };
        if self.current.as_ref().is_some_and(|c| first.better_than(c)) {
            self.current = Some(first.clone());
        }
        keep_best(&mut self.best, &first);
    }

    fn validate(&self, space: &StateSpace<'_>) -> Result<(), String> {
        self.params.check("params.").map_err(|e| e.to_string())?;
        check_points(&self.seeds, self.best.as_ref(), space)?;
        if let Some(c) = &self.current {
            check_evaluated("current", c, space)?;
            check_len("k", &self.k, space.dim())?;
            check_len("t0", &self.t0, space.dim())?;
            if self.best.is_none() {
                return Err("best is missing while current is set".into());
            }
        }
        // Annealing times count up from 0 and temperatures start positive.
        let time = |v: f64| v >= 0.0;
        let temperature = |v: f64| v > 0.0;
        check_all("k", &self.k, true, time, "must not be negative")?;
        check_all(
            "k_accept",
            &[self.k_accept],
            false,
            time,
            "must not be negative",
        )?;
        check_all("t0", &self.t0, true, temperature, "must be positive")?;
        check_all(
            "t0_accept",
            &[self.t0_accept],
            false,
            temperature,
            "must be positive",
        )
    }
}

/// Checks that every value of the state field `field` satisfies `ok` (a NaN never does); the
/// error names the value (`k[3] = -1`, or `k_accept = -1` for a field of one number, given as
/// a slice of one with `indexed` false).
fn check_all(
    field: &str,
    values: &[f64],
    indexed: bool,
    ok: impl Fn(f64) -> bool,
    why: &str,
) -> Result<(), String> {
    match values.iter().position(|&v| !ok(v)) {
        None => Ok(()),
        Some(i) if indexed => Err(format!("{field}[{i}] = {}: {why}", Num(values[i]))),
        Some(i) => Err(format!("{field} = {}: {why}", Num(values[i]))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Settings read back from a checkpoint obey a scenario's rules: a batch of 2^40 asked
    /// for memory, a ratio of 0 or a temperature of 0 would stall the schedule.
    #[test]
    fn restored_settings_are_checked() {
        assert!(AsaParams::default().check("params.").is_ok());
        let with = |change: fn(&mut AsaParams)| {
            let mut p = AsaParams::default();
            change(&mut p);
            p
        };
        for (p, says) in [
            (
                with(|p| p.batch = 1 << 40),
                "params.batch = 1099511627776: must be at most 10000 (the limit)",
            ),
            (
                with(|p| p.temperature_ratio = 0.0),
                "params.temperature_ratio = 0: must lie in (0, 1]",
            ),
            (
                with(|p| p.initial_temperature = f64::NAN),
                "params.initial_temperature = NaN",
            ),
            (
                with(|p| p.reanneal_interval = 0),
                "params.reanneal_interval = 0",
            ),
        ] {
            let e = p.check("params.").unwrap_err().to_string();
            assert!(e.starts_with(says), "{e}");
        }
    }
}
