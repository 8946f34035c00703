//! Particle swarm optimisation with a decreasing inertia weight and bounded velocities
//! (Kennedy & Eberhart 1995; Shi & Eberhart 1998), in two variants:
//!
//! * `comprehensive` (default): comprehensive-learning PSO (Liang, Qin, Suganthan, Baskar,
//!   IEEE TEC 2006). Each particle learns every coordinate from the personal best of some
//!   particle (its own, or with probability `Pc_i` the better of two others, chosen anew after
//!   `refresh` steps without improvement). Slower to collapse onto one basin, so it copes with
//!   multimodal costs such as Rastrigin's, and the reachability landscape.
//! * `global`: the classic swarm, pulled toward its own best and the swarm's best.

use super::{
    best_distinct, check_evaluated, check_len, check_point, check_points, keep_best, random_point,
    Evaluated, Optimizer, StateSpace, StepContext, StepReport,
};
use crate::error::Num;
use crate::limits::{MAX_POPULATION, MAX_SETTING};
use crate::scenario::{check_count, check_non_negative_within};
use rand::RngExt;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

/// How particles choose whom to follow.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Learning {
    /// Comprehensive learning (CLPSO).
    #[default]
    Comprehensive,
    /// Own best and swarm best (gbest).
    Global,
}

/// PSO settings (`[optimizer.pso]`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PsoParams {
    /// Particles. Default 32. A scenario sets it with `optimizer.population`: its
    /// `[optimizer.pso]` leaves it out, which reads as 0
    /// ([`crate::optimize::ga::FOLLOWS_POPULATION`]).
    #[serde(
        default = "crate::optimize::ga::follows_population",
        skip_serializing_if = "crate::optimize::ga::is_following_population"
    )]
    pub swarm: usize,
    /// Variant. Default `comprehensive`.
    pub learning: Learning,
    /// Inertia weight `w` at the start. Default 0.9.
    pub inertia: f64,
    /// Inertia weight at the end: `w` falls linearly with progress. Default 0.4.
    pub inertia_end: f64,
    /// Acceleration toward the exemplar (`comprehensive`) or the own best (`global`).
    /// Default 1.49445.
    pub cognitive: f64,
    /// Acceleration toward the swarm's best (`global` only). Default 1.49445.
    pub social: f64,
    /// Largest velocity per axis, as a fraction of the axis's range. Default 0.2.
    pub max_velocity: f64,
    /// Steps without improvement before a particle picks new exemplars (`comprehensive`).
    /// Default 7.
    pub refresh: usize,
}

impl Default for PsoParams {
    fn default() -> Self {
        PsoParams {
            swarm: 32,
            learning: Learning::Comprehensive,
            inertia: 0.9,
            inertia_end: 0.4,
            cognitive: 1.49445,
            social: 1.49445,
            max_velocity: 0.2,
            refresh: 7,
        }
    }
}

impl PsoParams {
    /// Checks the settings, with field names under `prefix`: a scenario's `[optimizer.pso]`
    /// (`optimizer.pso.`, with the swarm of `optimizer.population`) and a checkpoint's state
    /// read back (`params.`) obey the same rules.
    pub fn check(&self, prefix: &str) -> crate::Result<()> {
        check_count(self.swarm, 2, MAX_POPULATION, format!("{prefix}swarm"))?;
        for (v, name) in [
            (self.inertia, "inertia"),
            (self.inertia_end, "inertia_end"),
            (self.cognitive, "cognitive"),
            (self.social, "social"),
            (self.max_velocity, "max_velocity"),
        ] {
            check_non_negative_within(v, MAX_SETTING, "", format!("{prefix}{name}"))?;
        }
        Ok(())
    }
}

#[derive(Clone, Debug, Serialize, Deserialize)]
struct Particle {
    x: Vec<f64>,
    v: Vec<f64>,
    best: Evaluated,
    /// Steps since `best` last improved.
    stale: usize,
    /// For each coordinate, the particle whose personal best it learns from.
    exemplar: Vec<usize>,
}

/// The swarm's state.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Pso {
    params: PsoParams,
    seeds: Vec<Vec<f64>>,
    particles: Vec<Particle>,
    best: Option<Evaluated>,
}

impl Pso {
    /// A swarm; `seeds` become the first particles' positions.
    pub fn new(params: PsoParams, seeds: Vec<Vec<f64>>) -> Self {
        Pso {
            params,
            seeds,
            particles: Vec::new(),
            best: None,
        }
    }

    /// Restores a swarm from [`Optimizer::save`] output.
    pub fn load(state: serde_json::Value) -> serde_json::Result<Self> {
        crate::strict::deserialize(state).map_err(serde_path_to_error::Error::into_inner)
    }

    /// CLPSO's learning probability of particle `i` of `n`.
    fn learning_probability(i: usize, n: usize) -> f64 {
        if n < 2 {
            return 0.0;
        }
        let t = 10.0 * i as f64 / (n - 1) as f64;
        0.05 + 0.45 * (t.exp() - 1.0) / (10f64.exp() - 1.0)
    }

    /// New exemplars for particle `i` (CLPSO): per coordinate, itself or the better of two
    /// others; at least one coordinate learns from another particle.
    fn choose_exemplars(&self, i: usize, rng: &mut ChaCha8Rng) -> Vec<usize> {
        let n = self.particles.len();
        let dim = self.particles[i].x.len();
        if n < 2 {
            return vec![i; dim];
        }
        let pc = Self::learning_probability(i, n);
        let other = |rng: &mut ChaCha8Rng| {
            let pick = |rng: &mut ChaCha8Rng| {
                let j = rng.random_range(0..n - 1);
                if j >= i {
                    j + 1
                } else {
                    j
                }
            };
            let (a, b) = (pick(rng), pick(rng));
            if self.particles[b].best.better_than(&self.particles[a].best) {
                b
            } else {
                a
            }
        };
        let mut ex: Vec<usize> = (0..dim)
            .map(|_| {
                if rng.random::<f64>() < pc {
                    other(rng)
                } else {
                    i
                }
            })
            .collect();
        if dim > 0 && ex.iter().all(|&e| e == i) {
            let d = rng.random_range(0..dim);
            ex[d] = other(rng);
        }
        ex
    }
}

impl Optimizer for Pso {
    fn name(&self) -> &'static str {
        "pso"
    }

    fn step(&mut self, ctx: StepContext<'_>) -> StepReport {
        let (lower, upper) = (ctx.problem.lower(), ctx.problem.upper());
        let batch = ctx.batch();
        let rng = ctx.rng;
        let vmax: Vec<f64> = lower
            .iter()
            .zip(upper)
            .map(|(l, u)| self.params.max_velocity * (u - l))
            .collect();
        let xs: Vec<Vec<f64>> = if self.particles.is_empty() {
            let n = self.params.swarm.max(2);
            let mut xs: Vec<Vec<f64>> = self.seeds.iter().take(n).cloned().collect();
            while xs.len() < n {
                xs.push(random_point(lower, upper, rng));
            }
            xs
        } else {
            if self.params.learning == Learning::Comprehensive {
                for i in 0..self.particles.len() {
                    if self.particles[i].stale >= self.params.refresh
                        || self.particles[i].exemplar.is_empty()
                    {
                        let ex = self.choose_exemplars(i, rng);
                        self.particles[i].exemplar = ex;
                        self.particles[i].stale = 0;
                    }
                }
            }
            let g = self
                .best
                .as_ref()
                .expect("a best after the first step")
                .x
                .clone();
            let bests: Vec<Vec<f64>> = self.particles.iter().map(|p| p.best.x.clone()).collect();
            let p = &self.params;
            let w = p.inertia + (p.inertia_end - p.inertia) * ctx.progress.clamp(0.0, 1.0);
            for particle in &mut self.particles {
                for i in 0..particle.x.len() {
                    let v = match p.learning {
                        Learning::Comprehensive => {
                            let target = bests[particle.exemplar[i]][i];
                            w * particle.v[i]
                                + p.cognitive * rng.random::<f64>() * (target - particle.x[i])
                        }
                        Learning::Global => {
                            let (r1, r2): (f64, f64) = (rng.random(), rng.random());
                            w * particle.v[i]
                                + p.cognitive * r1 * (particle.best.x[i] - particle.x[i])
                                + p.social * r2 * (g[i] - particle.x[i])
                        }
                    };
                    let v = v.clamp(-vmax[i], vmax[i]);
                    let x = particle.x[i] + v;
                    // At a bound the particle stops there and loses that velocity component.
                    if x < lower[i] || x > upper[i] {
                        particle.x[i] = x.clamp(lower[i], upper[i]);
                        particle.v[i] = 0.0;
                    } else {
                        particle.x[i] = x;
                        particle.v[i] = v;
                    }
                }
            }
            self.particles.iter().map(|p| p.x.clone()).collect()
        };
        let evaluations = xs.len() as u64;
        let evaluated = match batch.evaluate(xs) {
            Ok(v) => v,
            Err(cut) => return StepReport::cut(cut),
        };
        if self.particles.is_empty() {
            for e in evaluated {
                let v = vmax
                    .iter()
                    .map(|m| {
                        if *m > 0.0 {
                            rng.random_range(-*m..=*m) * 0.5
                        } else {
                            0.0
                        }
                    })
                    .collect();
                keep_best(&mut self.best, &e);
                self.particles.push(Particle {
                    x: e.x.clone(),
                    v,
                    best: e,
                    stale: 0,
                    exemplar: Vec::new(),
                });
            }
        } else {
            for (particle, e) in self.particles.iter_mut().zip(evaluated) {
                keep_best(&mut self.best, &e);
                if e.better_than(&particle.best) {
                    particle.best = e;
                    particle.stale = 0;
                } else {
                    particle.stale += 1;
                }
            }
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
        serde_json::to_value(self).expect("PSO state serialises")
    }

    fn candidates(&self) -> Vec<&Evaluated> {
        self.particles
            .iter()
            .map(|p| &p.best)
            .chain(self.best.as_ref())
            .collect()
    }

    fn emigrants(&self, count: usize) -> Vec<Evaluated> {
        best_distinct(self.particles.iter().map(|p| &p.best), count)
    }

    fn immigrate(&mut self, migrants: &[Evaluated]) {
        let mut order: Vec<usize> = (0..self.particles.len()).collect();
        order.sort_by(|&a, &b| {
            self.particles[b]
                .best
                .cost
                .total_cmp(&self.particles[a].best.cost)
                .then(b.cmp(&a))
        });
        for (&slot, m) in order.iter().zip(migrants) {
            let p = &mut self.particles[slot];
            p.x = m.x.clone();
            p.best = m.clone();
            p.stale = 0;
        }
        for m in migrants {
            keep_best(&mut self.best, m);
        }
    }

    fn validate(&self, space: &StateSpace<'_>) -> Result<(), String> {
        self.params.check("params.").map_err(|e| e.to_string())?;
        check_points(&self.seeds, self.best.as_ref(), space)?;
        let (n, dim) = (self.particles.len(), space.dim());
        for (i, p) in self.particles.iter().enumerate() {
            check_point(&format!("particles[{i}].x"), &p.x, space)?;
            check_len(&format!("particles[{i}].v"), &p.v, dim)?;
            // A velocity is clamped to `max_velocity` times its variable's range.
            for (k, &v) in p.v.iter().enumerate() {
                let vmax = self.params.max_velocity * (space.upper[k] - space.lower[k]);
                if v.is_nan() || v.abs() > vmax {
                    return Err(format!(
                        "particles[{i}].v[{k}] = {}: beyond the largest velocity {}",
                        Num(v),
                        Num(vmax)
                    ));
                }
            }
            check_evaluated(&format!("particles[{i}].best"), &p.best, space)?;
            if !p.exemplar.is_empty() && p.exemplar.len() != dim {
                return Err(format!(
                    "particles[{i}].exemplar has {} values, the design space {dim}",
                    p.exemplar.len()
                ));
            }
            if let Some(e) = p.exemplar.iter().find(|&&e| e >= n) {
                return Err(format!(
                    "particles[{i}].exemplar names particle {e}: there are {n}"
                ));
            }
        }
        if n > 0 && self.best.is_none() {
            return Err("best is missing while the swarm is not empty".into());
        }
        Ok(())
    }
}
