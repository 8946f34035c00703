//! Particle swarm optimisation with an inertia weight and bounded velocities (Kennedy &
//! Eberhart 1995; constriction-equivalent coefficients of Clerc & Kennedy 2002).

use super::{
    evaluate_batch, keep_best, random_point, Evaluated, Optimizer, StepContext, StepReport,
};
use rand::RngExt;
use serde::{Deserialize, Serialize};

/// PSO settings (`[optimizer.pso]`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PsoParams {
    /// Particles. Default 32.
    pub swarm: usize,
    /// Inertia weight `w`. Default 0.7298.
    pub inertia: f64,
    /// Pull toward the particle's own best `c1`. Default 1.49618.
    pub cognitive: f64,
    /// Pull toward the swarm's best `c2`. Default 1.49618.
    pub social: f64,
    /// Largest velocity per axis, as a fraction of the axis's range. Default 0.2.
    pub max_velocity: f64,
}

impl Default for PsoParams {
    fn default() -> Self {
        PsoParams {
            swarm: 32,
            inertia: 0.7298,
            cognitive: 1.49618,
            social: 1.49618,
            max_velocity: 0.2,
        }
    }
}

#[derive(Clone, Debug, Serialize, Deserialize)]
struct Particle {
    x: Vec<f64>,
    v: Vec<f64>,
    best: Evaluated,
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
        serde_json::from_value(state)
    }
}

impl Optimizer for Pso {
    fn name(&self) -> &'static str {
        "pso"
    }

    fn step(&mut self, ctx: StepContext<'_>) -> StepReport {
        let (lower, upper) = (ctx.problem.lower(), ctx.problem.upper());
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
            let g = self
                .best
                .as_ref()
                .expect("a best after the first step")
                .x
                .clone();
            let p = &self.params;
            for particle in &mut self.particles {
                for i in 0..particle.x.len() {
                    let (r1, r2): (f64, f64) = (rng.random(), rng.random());
                    let v = p.inertia * particle.v[i]
                        + p.cognitive * r1 * (particle.best.x[i] - particle.x[i])
                        + p.social * r2 * (g[i] - particle.x[i]);
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
        let evaluated = evaluate_batch(ctx.problem, xs, ctx.first_stream, ctx.progress);
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
                });
            }
        } else {
            for (particle, e) in self.particles.iter_mut().zip(evaluated) {
                keep_best(&mut self.best, &e);
                if e.better_than(&particle.best) {
                    particle.best = e;
                }
            }
        }
        StepReport { evaluations }
    }

    fn best(&self) -> Option<&Evaluated> {
        self.best.as_ref()
    }

    fn save(&self) -> serde_json::Value {
        serde_json::to_value(self).expect("PSO state serialises")
    }
}
