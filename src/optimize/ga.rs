//! A real-coded genetic algorithm: binary tournament selection, simulated binary crossover
//! (SBX, Deb & Agrawal 1995), polynomial mutation (Deb & Goyal 1996), a topology mutation that
//! sets a variable to zero, and elitism.

use super::{
    best_distinct, check_evaluated, check_points, keep_best, random_point, Evaluated, Optimizer,
    StateSpace, StepContext, StepReport,
};
use crate::limits::{MAX_POPULATION, MAX_SETTING};
use crate::scenario::{check, check_count, check_non_negative_within};
use rand::RngExt;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

/// GA settings (`[optimizer.ga]`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct GaParams {
    /// Individuals per generation. Default 32. A scenario sets it with `optimizer.population`:
    /// its `[optimizer.ga]` leaves it out, which reads as 0 ([`FOLLOWS_POPULATION`]).
    #[serde(
        default = "follows_population",
        skip_serializing_if = "is_following_population"
    )]
    pub population: usize,
    /// Individuals carried unchanged into the next generation. Default 2.
    pub elites: usize,
    /// Tournament size. Default 2.
    pub tournament: usize,
    /// Probability that a pair of parents is crossed. Default 0.9.
    pub crossover_rate: f64,
    /// SBX distribution index `η_c`. Default 15.
    pub eta_crossover: f64,
    /// Polynomial-mutation distribution index `η_m`. Default 20.
    pub eta_mutation: f64,
    /// Per-variable mutation probability. Default: 1 / dimension.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mutation_rate: Option<f64>,
    /// Per-variable probability of setting a variable to 0 (when 0 is within its bounds): the
    /// move that removes a link or a joint in one step. Default: 0.5 / dimension.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub zero_rate: Option<f64>,
}

/// The value of [`GaParams::population`] and [`crate::optimize::pso::PsoParams::swarm`] in a
/// scenario's `[optimizer.ga]` and `[optimizer.pso]` that leave it out: the size is
/// `optimizer.population`'s, which the scenario sets for every algorithm.
pub const FOLLOWS_POPULATION: usize = 0;

/// [`FOLLOWS_POPULATION`], for serde.
pub(crate) fn follows_population() -> usize {
    FOLLOWS_POPULATION
}

/// True for [`FOLLOWS_POPULATION`], which is not written.
pub(crate) fn is_following_population(n: &usize) -> bool {
    *n == FOLLOWS_POPULATION
}

impl Default for GaParams {
    fn default() -> Self {
        GaParams {
            population: 32,
            elites: 2,
            tournament: 2,
            crossover_rate: 0.9,
            eta_crossover: 15.0,
            eta_mutation: 20.0,
            mutation_rate: None,
            zero_rate: None,
        }
    }
}

impl GaParams {
    /// Checks the settings, with field names under `prefix`: a scenario's `[optimizer.ga]`
    /// (`optimizer.ga.`, with the population of `optimizer.population`) and a checkpoint's
    /// state read back (`params.`) obey the same rules, so that no setting can stall or
    /// exhaust memory.
    pub fn check(&self, prefix: &str) -> crate::Result<()> {
        let field = |name: &str| format!("{prefix}{name}");
        check_count(self.population, 2, MAX_POPULATION, field("population"))?;
        check(
            self.elites < self.population,
            field("elites"),
            self.elites,
            &format!(
                "must be less than the population ({}): a generation needs children",
                self.population
            ),
        )?;
        check_count(self.tournament, 1, MAX_POPULATION, field("tournament"))?;
        let rates = [
            ("crossover_rate", Some(self.crossover_rate)),
            ("mutation_rate", self.mutation_rate),
            ("zero_rate", self.zero_rate),
        ];
        for (name, rate) in rates {
            if let Some(v) = rate {
                let ok = (0.0..=1.0).contains(&v);
                check(ok, field(name), v, "must be a probability in [0, 1]")?;
            }
        }
        check_non_negative_within(self.eta_crossover, MAX_SETTING, "", field("eta_crossover"))?;
        check_non_negative_within(self.eta_mutation, MAX_SETTING, "", field("eta_mutation"))
    }
}

/// The genetic algorithm's state.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Ga {
    params: GaParams,
    seeds: Vec<Vec<f64>>,
    population: Vec<Evaluated>,
    best: Option<Evaluated>,
}

impl Ga {
    /// A GA; `seeds` are points put into the first generation (the rest is uniform random).
    pub fn new(params: GaParams, seeds: Vec<Vec<f64>>) -> Self {
        Ga {
            params,
            seeds,
            population: Vec::new(),
            best: None,
        }
    }

    /// Restores a GA from [`Optimizer::save`] output.
    pub fn load(state: serde_json::Value) -> serde_json::Result<Self> {
        crate::strict::deserialize(state).map_err(serde_path_to_error::Error::into_inner)
    }

    fn tournament(&self, rng: &mut ChaCha8Rng) -> usize {
        let n = self.population.len();
        let mut best = rng.random_range(0..n);
        for _ in 1..self.params.tournament.max(1) {
            let c = rng.random_range(0..n);
            if self.population[c].better_than(&self.population[best]) {
                best = c;
            }
        }
        best
    }
}

/// Simulated binary crossover of one variable within `[lo, hi]` (bounded form).
fn sbx(x1: f64, x2: f64, lo: f64, hi: f64, eta: f64, rng: &mut ChaCha8Rng) -> (f64, f64) {
    if (x1 - x2).abs() < 1e-14 || hi <= lo {
        return (x1, x2);
    }
    let (y1, y2) = if x1 < x2 { (x1, x2) } else { (x2, x1) };
    let u: f64 = rng.random();
    let spread = |beta: f64| {
        let alpha = 2.0 - beta.powf(-(eta + 1.0));
        if u <= 1.0 / alpha {
            (u * alpha).powf(1.0 / (eta + 1.0))
        } else {
            (1.0 / (2.0 - u * alpha)).powf(1.0 / (eta + 1.0))
        }
    };
    let b1 = spread(1.0 + 2.0 * (y1 - lo) / (y2 - y1));
    let b2 = spread(1.0 + 2.0 * (hi - y2) / (y2 - y1));
    let c1 = (0.5 * ((y1 + y2) - b1 * (y2 - y1))).clamp(lo, hi);
    let c2 = (0.5 * ((y1 + y2) + b2 * (y2 - y1))).clamp(lo, hi);
    if rng.random::<bool>() {
        (c2, c1)
    } else {
        (c1, c2)
    }
}

/// Polynomial mutation of one variable within `[lo, hi]`.
fn polynomial(x: f64, lo: f64, hi: f64, eta: f64, rng: &mut ChaCha8Rng) -> f64 {
    if hi <= lo {
        return x;
    }
    let range = hi - lo;
    let (d1, d2) = ((x - lo) / range, (hi - x) / range);
    let u: f64 = rng.random();
    let p = 1.0 / (eta + 1.0);
    let dq = if u < 0.5 {
        let v = 2.0 * u + (1.0 - 2.0 * u) * (1.0 - d1).powf(eta + 1.0);
        v.powf(p) - 1.0
    } else {
        let v = 2.0 * (1.0 - u) + 2.0 * (u - 0.5) * (1.0 - d2).powf(eta + 1.0);
        1.0 - v.powf(p)
    };
    (x + dq * range).clamp(lo, hi)
}

impl Optimizer for Ga {
    fn name(&self) -> &'static str {
        "ga"
    }

    fn step(&mut self, ctx: StepContext<'_>) -> StepReport {
        let (lower, upper) = (ctx.problem.lower(), ctx.problem.upper());
        let dim = lower.len();
        let n = self.params.population.max(2);
        let batch = ctx.batch();
        let rng = ctx.rng;
        let xs: Vec<Vec<f64>> = if self.population.is_empty() {
            let mut xs: Vec<Vec<f64>> = self.seeds.iter().take(n).cloned().collect();
            while xs.len() < n {
                xs.push(random_point(lower, upper, rng));
            }
            xs
        } else {
            let pm = self.params.mutation_rate.unwrap_or(1.0 / dim.max(1) as f64);
            let pz = self.params.zero_rate.unwrap_or(0.5 / dim.max(1) as f64);
            let elites = self.params.elites.min(n);
            let mut children = Vec::with_capacity(n - elites);
            while children.len() < n - elites {
                let a = self.population[self.tournament(rng)].x.clone();
                let b = self.population[self.tournament(rng)].x.clone();
                let (mut c1, mut c2) = (a.clone(), b.clone());
                if rng.random::<f64>() < self.params.crossover_rate {
                    for i in 0..dim {
                        if rng.random::<bool>() {
                            (c1[i], c2[i]) = sbx(
                                a[i],
                                b[i],
                                lower[i],
                                upper[i],
                                self.params.eta_crossover,
                                rng,
                            );
                        }
                    }
                }
                for c in [&mut c1, &mut c2] {
                    for i in 0..dim {
                        if rng.random::<f64>() < pm {
                            c[i] =
                                polynomial(c[i], lower[i], upper[i], self.params.eta_mutation, rng);
                        }
                        if lower[i] <= 0.0 && upper[i] >= 0.0 && rng.random::<f64>() < pz {
                            c[i] = 0.0;
                        }
                    }
                }
                children.push(c1);
                if children.len() < n - elites {
                    children.push(c2);
                }
            }
            children
        };
        let evaluations = xs.len() as u64;
        let evaluated = match batch.evaluate(xs) {
            Ok(v) => v,
            Err(cut) => return StepReport::cut(cut),
        };
        for e in &evaluated {
            keep_best(&mut self.best, e);
        }
        if self.population.is_empty() {
            self.population = evaluated;
        } else {
            // Elitism: the best of the old generation survive.
            self.population.sort_by(|a, b| a.cost.total_cmp(&b.cost));
            self.population.truncate(self.params.elites.min(n));
            self.population.extend(evaluated);
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
        serde_json::to_value(self).expect("GA state serialises")
    }

    fn candidates(&self) -> Vec<&Evaluated> {
        self.population.iter().chain(self.best.as_ref()).collect()
    }

    fn emigrants(&self, count: usize) -> Vec<Evaluated> {
        best_distinct(&self.population, count)
    }

    fn immigrate(&mut self, migrants: &[Evaluated]) {
        // The worst members make room (the order of the others is kept: it is part of the
        // state that selection reads).
        let mut order: Vec<usize> = (0..self.population.len()).collect();
        order.sort_by(|&a, &b| {
            self.population[b]
                .cost
                .total_cmp(&self.population[a].cost)
                .then(b.cmp(&a))
        });
        for (&slot, m) in order.iter().zip(migrants) {
            self.population[slot] = m.clone();
        }
        for m in migrants {
            keep_best(&mut self.best, m);
        }
    }

    fn validate(&self, space: &StateSpace<'_>) -> Result<(), String> {
        self.params.check("params.").map_err(|e| e.to_string())?;
        check_points(&self.seeds, self.best.as_ref(), space)?;
        for (i, e) in self.population.iter().enumerate() {
            check_evaluated(&format!("population[{i}]"), e, space)?;
        }
        if !self.population.is_empty() && self.best.is_none() {
            return Err("best is missing while the population is not empty".into());
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn operators_stay_in_bounds() {
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        for _ in 0..10_000 {
            let (a, b) = (rng.random_range(-1.0..2.0), rng.random_range(-1.0..2.0));
            let (c1, c2) = sbx(a, b, -1.0, 2.0, 15.0, &mut rng);
            assert!((-1.0..=2.0).contains(&c1) && (-1.0..=2.0).contains(&c2));
            let m = polynomial(a, -1.0, 2.0, 20.0, &mut rng);
            assert!((-1.0..=2.0).contains(&m));
        }
    }

    #[test]
    fn sbx_children_keep_the_parents_mean_on_average() {
        let mut rng = ChaCha8Rng::seed_from_u64(2);
        let mut sum = 0.0;
        for _ in 0..20_000 {
            let (c1, c2) = sbx(0.2, 0.6, -10.0, 10.0, 15.0, &mut rng);
            sum += c1 + c2;
        }
        assert!((sum / 20_000.0 - 0.8).abs() < 0.01);
    }
}
