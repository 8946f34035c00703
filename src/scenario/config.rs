//! Settings sections of a scenario: planner, objective weights, optimiser. Every field has a
//! documented default so a scenario may leave a section out.

use crate::optimize::asa::AsaParams;
use crate::optimize::ga::GaParams;
use crate::optimize::islands::Migration;
use crate::optimize::pso::PsoParams;
use serde::{Deserialize, Serialize};

/// The `[objective]` section: weights `λ0 … λ5` of paper Eq. 23.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ObjectiveWeights {
    /// `λ0`, on the unreached share `1 − R`. Default 10.
    pub lambda0: f64,
    /// `λ1`, on `A_i = atan(a_i)` (link length). Default 1.
    pub lambda1: f64,
    /// `λ2`, on `B_i = Σ atan(max − min)` (joint ranges). Default 0.2.
    pub lambda2: f64,
    /// `λ3`, on `C_i` (link kept). Default 0.5.
    pub lambda3: f64,
    /// `λ4`, on `D_i` (joint kept). Default 0.5.
    pub lambda4: f64,
    /// `λ5`, on `E` (some task unreached). Default 20.
    pub lambda5: f64,
}

impl Default for ObjectiveWeights {
    fn default() -> Self {
        ObjectiveWeights {
            lambda0: 10.0,
            lambda1: 1.0,
            lambda2: 0.2,
            lambda3: 0.5,
            lambda4: 0.5,
            lambda5: 20.0,
        }
    }
}

impl ObjectiveWeights {
    /// The weights as an array `[λ0, …, λ5]`.
    pub fn as_array(&self) -> [f64; 6] {
        [
            self.lambda0,
            self.lambda1,
            self.lambda2,
            self.lambda3,
            self.lambda4,
            self.lambda5,
        ]
    }
}

/// Optimisation algorithm, chosen by name in `optimizer.algorithm` and `--optimizer`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Algorithm {
    /// Real-coded genetic algorithm.
    #[default]
    Ga,
    /// Particle swarm optimisation.
    Pso,
    /// Adaptive simulated annealing.
    Asa,
}

impl Algorithm {
    /// Its name, as scenarios, the command line and `best.json` write it (`ga`, `pso`, `asa`).
    pub fn name(self) -> &'static str {
        match self {
            Algorithm::Ga => "ga",
            Algorithm::Pso => "pso",
            Algorithm::Asa => "asa",
        }
    }
}

/// The `[optimizer]` section.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct OptimizerConfig {
    /// Algorithm. Default `ga`.
    pub algorithm: Algorithm,
    /// Population (GA) or swarm (PSO) size. Default 32.
    pub population: usize,
    /// Stop once `R = 1` and the best cost has not improved for this many generations.
    /// Default 30.
    pub patience: usize,
    /// Wall-clock budget in seconds. Default 60.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub time_limit: Option<f64>,
    /// Budget in objective evaluations. Default: none.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub evaluations: Option<u64>,
    /// Seconds between checkpoints. Default 10.
    pub checkpoint_interval: f64,
    /// Fresh planner seeds the best distinct final candidates are re-checked with before a
    /// run ends; the result is the candidate whose cost is lowest with its lowest `R` over
    /// them (0: no re-check). Default 8.
    pub recheck_seeds: usize,
    /// Extra planner runs, on their own random streams, that confirm every `R = 1` an
    /// evaluation claims during the run; the first that falls short sets `R`. Default 3.
    pub confirm_seeds: usize,
    /// Migration between islands (`kinsynth optimize --islands`): every `interval`
    /// generations each island sends its best `count` designs to the next. Default 10 and 2.
    pub migration: Migration,
    /// GA settings (its `population` is `population`'s).
    pub ga: GaParams,
    /// PSO settings (its `swarm` is `population`'s).
    pub pso: PsoParams,
    /// ASA settings.
    pub asa: AsaParams,
}

impl Default for OptimizerConfig {
    fn default() -> Self {
        OptimizerConfig {
            algorithm: Algorithm::Ga,
            population: 32,
            patience: 30,
            time_limit: Some(60.0),
            evaluations: None,
            checkpoint_interval: 10.0,
            recheck_seeds: 8,
            confirm_seeds: 3,
            migration: Migration::default(),
            // Their sizes are `population`'s (and so not written to a scenario).
            ga: GaParams {
                population: crate::optimize::ga::FOLLOWS_POPULATION,
                ..GaParams::default()
            },
            pso: PsoParams {
                swarm: crate::optimize::ga::FOLLOWS_POPULATION,
                ..PsoParams::default()
            },
            asa: AsaParams::default(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An algorithm's name is the one scenarios write (and so `best.json`'s `optimizer`).
    #[test]
    fn algorithm_names_are_their_serialised_names() {
        for a in [Algorithm::Ga, Algorithm::Pso, Algorithm::Asa] {
            assert_eq!(serde_json::to_value(a).unwrap(), a.name());
        }
    }
}
