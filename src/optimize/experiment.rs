//! The paper's experiments (§IV): several random workspaces, each optimised by several methods
//! under the same wall-clock budget; curves averaged over the workspaces, like Fig. 2 and 3.

use super::runner::{HistoryRow, Quiet, RunOptions, RunSummary, Runner};
use crate::collision::CheckerKind;
use crate::error::Result;
use crate::io::write_atomic;
use crate::scenario::preset::{self, Preset};
use crate::scenario::{Algorithm, Scenario};
use plotters::prelude::*;
use serde::{Deserialize, Serialize};
use std::path::Path;
use std::sync::atomic::AtomicBool;

/// One method of a comparison: an optimiser with an edge checker and a step bound.
#[derive(Clone, Debug, PartialEq)]
pub struct Method {
    /// Label in tables and plots.
    pub label: String,
    /// Optimiser.
    pub algorithm: Algorithm,
    /// Edge checker.
    pub checker: CheckerKind,
    /// Step bound `L_max`.
    pub l_max: f64,
    /// Plan as the paper's RRT does: from home alone, within the fixed iteration budget, its
    /// inverse kinematics clamping whole steps into the ranges, each step tried whole first
    /// (`postures = 0`, `budget_growth = 1`, `ik_hold_limits = false`, `aimed_steering =
    /// false`); otherwise with the scenario's planner settings.
    pub paper_planner: bool,
}

/// The methods of an experiment: §IV-A compares GA, PSO and ASA with `certified` (the
/// default, proven-safe checker) at π/4, GA with the paper's `segment` fast path at π/4, and the
/// paper's baseline, ASA + `discrete` at π/40 with the paper's planner (no backward trees, a
/// fixed budget), also run with the scenario's planner; §IV-B runs GA with `certified` at π/4.
pub fn methods(preset: Preset) -> Vec<Method> {
    use std::f64::consts::PI;
    let m = |label: &str, algorithm, checker, l_max| Method {
        label: label.into(),
        algorithm,
        checker,
        l_max,
        paper_planner: false,
    };
    let certified = CheckerKind::Certified;
    match preset {
        Preset::Paper2d => vec![
            m("GA certified pi/4", Algorithm::Ga, certified, PI / 4.0),
            m("PSO certified pi/4", Algorithm::Pso, certified, PI / 4.0),
            m("ASA certified pi/4", Algorithm::Asa, certified, PI / 4.0),
            m(
                "GA segment pi/4",
                Algorithm::Ga,
                CheckerKind::Segment,
                PI / 4.0,
            ),
            Method {
                paper_planner: true,
                ..m(
                    "ASA discrete pi/40 (baseline)",
                    Algorithm::Asa,
                    CheckerKind::Discrete,
                    PI / 40.0,
                )
            },
            m(
                "ASA discrete pi/40 with this planner",
                Algorithm::Asa,
                CheckerKind::Discrete,
                PI / 40.0,
            ),
        ],
        Preset::Paper3d => vec![m("GA certified pi/4", Algorithm::Ga, certified, PI / 4.0)],
    }
}

/// One finished run of an experiment.
#[derive(Clone, Debug)]
pub struct RunRecord {
    /// Workspace index.
    pub workspace: usize,
    /// Method index.
    pub method: usize,
    /// The run's result.
    pub summary: RunSummary,
    /// Its history.
    pub history: Vec<HistoryRow>,
}

impl RunRecord {
    /// Seconds until the best design first reached `R = 1`, if it did.
    pub fn time_to_full_reach(&self) -> Option<f64> {
        self.history
            .iter()
            .find(|r| r.best_reachability >= 1.0)
            .map(|r| r.elapsed_s)
    }
}

/// Reads one quantity off a history row.
type Metric = fn(&HistoryRow) -> f64;

/// The value of a step-function history at time `t` (the last row at or before `t`).
fn at(history: &[HistoryRow], t: f64, f: fn(&HistoryRow) -> f64) -> Option<f64> {
    history.iter().rev().find(|r| r.elapsed_s <= t).map(f)
}

/// Median of the values, `None` for none.
pub fn median(mut v: Vec<f64>) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    Some(if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    })
}

/// One slice of an experiment's workspaces: the `index`-th (from 1) of `count` (`--shard K/N`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Shard {
    /// Which slice, from 1.
    pub index: usize,
    /// Number of slices.
    pub count: usize,
}

impl Shard {
    /// The whole experiment: slice 1 of 1.
    pub const WHOLE: Shard = Shard { index: 1, count: 1 };

    /// What is wrong with the slice, if anything: `N` must lie in `1..=`[`MAX_SHARDS`] and `K`
    /// in `1..=N` (checked before [`Shard::workspaces`] divides by `N`).
    pub fn problem(&self) -> Option<String> {
        if self.count == 0 || self.count > MAX_SHARDS {
            Some(format!("N must lie in 1..={MAX_SHARDS}"))
        } else if !(1..=self.count).contains(&self.index) {
            Some("K must lie in 1..=N".into())
        } else {
            None
        }
    }

    /// The workspaces of this slice out of `runs`: a contiguous range, the slices of one
    /// experiment covering `0 … runs−1` exactly once (some may be empty when `count > runs`).
    pub fn workspaces(&self, runs: usize) -> std::ops::Range<usize> {
        let (k, n) = (self.index - 1, self.count);
        (k * runs / n)..((k + 1) * runs / n)
    }
}

impl std::str::FromStr for Shard {
    type Err = crate::Error;
    /// Parses `K/N` with `1 ≤ K ≤ N` (Slurm: `--shard $SLURM_ARRAY_TASK_ID/$SLURM_ARRAY_TASK_COUNT`
    /// with `--array=1-N`).
    fn from_str(s: &str) -> Result<Self> {
        let bad = |why: &str| crate::Error::invalid("--shard", s, why);
        let (k, n) = s
            .split_once('/')
            .ok_or_else(|| bad("must be K/N, e.g. 2/4"))?;
        let parse = |t: &str| t.trim().parse::<usize>().ok();
        let (Some(index), Some(count)) = (parse(k), parse(n)) else {
            return Err(bad("must be K/N with whole numbers K and N, e.g. 2/4"));
        };
        let shard = Shard { index, count };
        match shard.problem() {
            Some(why) => Err(bad(&why)),
            None => Ok(shard),
        }
    }
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

/// The largest number of slices of an experiment (and of workspaces).
pub const MAX_SHARDS: usize = 100_000;

/// How an experiment is set up.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ExperimentSpec {
    /// The paper's experiment: paper-2d (§IV-A) or paper-3d (§IV-B).
    pub preset: Preset,
    /// Number of random workspaces of the whole experiment.
    pub runs: usize,
    /// Seconds per run (also the time axis of the curves).
    pub time_limit: f64,
    /// Evaluations per run, if capped: with it (and a time limit that is not reached) every
    /// result but the times depends on the seeds only.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub evaluations: Option<u64>,
    /// Seed of the first workspace (the others follow).
    pub seed: u64,
}

/// `experiment.json`: what an experiment's folder holds, for `kinsynth merge`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Manifest {
    /// The experiment.
    pub spec: ExperimentSpec,
    /// The slice this folder holds.
    pub shard: Shard,
    /// Its workspaces.
    pub workspaces: Vec<usize>,
}

/// Name of the manifest file in an experiment's folder.
pub const MANIFEST: &str = "experiment.json";

/// Runs the experiment, or the slice `shard` of it: the workspaces of [`Shard::workspaces`] of
/// `spec.preset` (workspace `w` has the seed `seed + w`), each optimised by every method of
/// [`methods`] for `time_limit` seconds (stopping early when converged, or at `evaluations`),
/// writing into `out`: each workspace's scenario and run folders, `runs.csv` (one line per
/// run), `curves.csv` (averaged curves on a time grid), `curves.svg` and `experiment.json`.
/// `log` receives a line per finished run.
pub fn run_experiment(
    spec: &ExperimentSpec,
    shard: Shard,
    out: &Path,
    log: &mut dyn FnMut(&str),
) -> Result<Vec<RunRecord>> {
    spec.validate()?;
    let (preset, time_limit, seed) = (spec.preset, spec.time_limit, spec.seed);
    let methods = methods(preset);
    let mut records = Vec::new();
    let workspaces = shard.workspaces(spec.runs);
    crate::io::check_output_dir(out)?;
    std::fs::create_dir_all(out).map_err(|source| crate::Error::Write {
        path: out.to_path_buf(),
        source,
    })?;
    for w in workspaces.clone() {
        let ws_seed = seed.saturating_add(w as u64); // within range: `validate`
        let spec_w = preset::generate(preset, ws_seed);
        let dir = out.join(format!("workspace{w}"));
        std::fs::create_dir_all(&dir).map_err(|source| crate::Error::Write {
            path: dir.clone(),
            source,
        })?;
        let scenario_path = dir.join("scenario.toml");
        write_atomic(&scenario_path, preset::to_toml(preset, &spec_w).as_bytes())?;
        let scenario = Scenario::load(&scenario_path)?;
        for (k, m) in methods.iter().enumerate() {
            let mut planner = scenario.planner.clone();
            planner.checker = m.checker;
            planner.l_max = m.l_max;
            planner.schedule = None;
            if m.paper_planner {
                planner.postures = 0;
                planner.budget_growth = 1;
                planner.ik_hold_limits = false;
                planner.aimed_steering = false;
            }
            let options = RunOptions {
                algorithm: m.algorithm,
                seed: ws_seed,
                time_limit: Some(time_limit),
                evaluations: spec.evaluations,
                patience: scenario.optimizer.patience,
                checkpoint_interval: 1e9, // only the final checkpoint
                // The paper's method as published: one planner run per evaluation, no final
                // re-check, so the times to R = 1 compare with its figures.
                recheck_seeds: 0,
                confirm_seeds: 0,
            };
            let run_dir = dir.join(format!("method{k}"));
            let runner = Runner::new(&scenario, &scenario_path, planner, options, &run_dir);
            let summary = runner.run(None, &AtomicBool::new(false), &mut Quiet)?;
            let history = Runner::read_checkpoint(&run_dir)?.history;
            let record = RunRecord {
                workspace: w,
                method: k,
                summary,
                history,
            };
            log(&format!(
                "workspace {w} {}: R = {:.2} (first R = 1 at {}), cost {:.3}, {} links, {} joints, {} evaluations",
                m.label,
                record.summary.reachability,
                record
                    .time_to_full_reach()
                    .map_or("never".to_string(), |t| format!("{t:.2} s")),
                record.summary.cost,
                record.summary.links_kept,
                record.summary.joints_kept,
                record.summary.evaluations
            ));
            records.push(record);
        }
    }
    write_tables(&methods, &records, time_limit, out)?;
    let manifest = Manifest {
        spec: spec.clone(),
        shard,
        workspaces: workspaces.collect(),
    };
    write_atomic(
        &out.join(MANIFEST),
        serde_json::to_string_pretty(&manifest)
            .expect("a manifest serialises")
            .as_bytes(),
    )?;
    Ok(records)
}

impl ExperimentSpec {
    /// Checks the settings; errors name the option (`--time-limit`, …) and the value.
    pub fn validate(&self) -> Result<()> {
        self.check(&|field| format!("--{}", field.replace('_', "-")))
    }

    /// Checks the settings as an `experiment.json` holds them; errors name its field
    /// (`spec.time_limit`, …) and the value.
    pub fn validate_manifest(&self) -> Result<()> {
        self.check(&|field| format!("spec.{field}"))
    }

    /// Checks the settings, naming each field as `name` gives it.
    fn check(&self, name: &dyn Fn(&str) -> String) -> Result<()> {
        use crate::limits::MAX_SECONDS;
        if !(self.time_limit.is_finite() && self.time_limit > 0.0 && self.time_limit <= MAX_SECONDS)
        {
            return Err(crate::Error::invalid(
                name("time_limit"),
                crate::error::Num(self.time_limit),
                format!("must be positive and at most {MAX_SECONDS} s"),
            ));
        }
        if self.evaluations == Some(0) {
            return Err(crate::Error::invalid(
                name("evaluations"),
                0,
                "must be at least 1",
            ));
        }
        if !(1..=MAX_SHARDS).contains(&self.runs) {
            return Err(crate::Error::invalid(
                name("runs"),
                self.runs,
                format!("must be from 1 to {MAX_SHARDS}"),
            ));
        }
        // Workspace `w` has the seed `seed + w`: every one must exist (no wrapping to 0).
        if self.seed.checked_add(self.runs as u64 - 1).is_none() {
            return Err(crate::Error::invalid(
                name("seed"),
                self.seed,
                format!(
                    "must be at most {} for {} runs (workspace w has the seed seed + w)",
                    u64::MAX - (self.runs as u64 - 1),
                    self.runs
                ),
            ));
        }
        Ok(())
    }

    /// The first setting in which `self` differs from `other`: its field name and the two
    /// values.
    fn difference(&self, other: &ExperimentSpec) -> Option<(&'static str, String, String)> {
        let evaluations = |e: Option<u64>| e.map_or("none".to_string(), |n| n.to_string());
        let fields = [
            (
                "preset",
                self.preset.name().to_string(),
                other.preset.name().to_string(),
            ),
            ("runs", self.runs.to_string(), other.runs.to_string()),
            (
                "time_limit",
                crate::error::Num(self.time_limit).to_string(),
                crate::error::Num(other.time_limit).to_string(),
            ),
            (
                "evaluations",
                evaluations(self.evaluations),
                evaluations(other.evaluations),
            ),
            ("seed", self.seed.to_string(), other.seed.to_string()),
        ];
        fields.into_iter().find(|(_, a, b)| a != b)
    }
}

/// A list of indices for a message: whole when short, else its first few and how many more.
fn brief(v: &[usize]) -> String {
    const SHOWN: usize = 5;
    let head: Vec<String> = v.iter().take(SHOWN).map(usize::to_string).collect();
    if v.len() <= SHOWN {
        format!("[{}]", head.join(", "))
    } else {
        format!("[{}, … and {} more]", head.join(", "), v.len() - SHOWN)
    }
}

/// Reads the `experiment.json` of an experiment folder.
pub fn read_manifest(dir: &Path) -> Result<Manifest> {
    let path = dir.join(MANIFEST);
    let text =
        crate::limits::read_text(&path, crate::limits::MAX_TEXT_FILE_BYTES).map_err(|source| {
            crate::Error::Read {
                path: path.clone(),
                source,
            }
        })?;
    let m: Manifest = crate::strict::deserialize(&mut serde_json::Deserializer::from_str(&text))
        .map_err(|e| crate::Error::Parse {
            file: path.clone(),
            message: e.to_string(),
        })?;
    m.spec.validate_manifest().map_err(|e| e.in_file(&path))?;
    // The slice as `--shard` accepts it, before its workspaces are computed from it.
    if let Some(why) = m.shard.problem() {
        return Err(crate::Error::invalid("shard", m.shard, why).in_file(&path));
    }
    let expected: Vec<usize> = m.shard.workspaces(m.spec.runs).collect();
    if m.workspaces != expected {
        return Err(crate::Error::invalid(
            "workspaces",
            brief(&m.workspaces),
            format!(
                "shard {} of {} runs holds {}",
                m.shard,
                m.spec.runs,
                brief(&expected)
            ),
        )
        .in_file(&path));
    }
    Ok(m)
}

/// Combines the folders of an experiment's slices (each written by [`run_experiment`] with
/// its own [`Shard`] of the same [`ExperimentSpec`]) into `out`: the `runs.csv`, `curves.csv`
/// and `curves.svg` that the whole experiment run at once writes from the same runs, and an
/// `experiment.json` of the whole. Every workspace must come from exactly one folder; the
/// runs' results and histories are read from their `best.json` and `checkpoint.json`.
pub fn merge(dirs: &[std::path::PathBuf], out: &Path) -> Result<Vec<RunRecord>> {
    let Some(first_dir) = dirs.first() else {
        return Err(crate::Error::invalid(
            "DIR",
            "none",
            "give the folders of the slices to merge",
        ));
    };
    // Each folder must be a slice (a folder that is not one is named as such first).
    let manifests: Vec<Manifest> = dirs
        .iter()
        .map(|d| read_manifest(d))
        .collect::<Result<_>>()?;
    // The slices' folders are only read: the tables written into one would replace its own.
    let slices: Vec<(&Path, String)> = dirs
        .iter()
        .map(|d| (d.as_path(), format!("the slice folder {}", d.display())))
        .collect();
    let slices: Vec<(&Path, &str)> = slices.iter().map(|(d, w)| (*d, w.as_str())).collect();
    crate::io::check_dir_outside("--out", out, &slices)?;
    crate::io::check_output_dir(out)?;
    let spec = manifests[0].spec.clone();
    let mut owner: Vec<Option<usize>> = vec![None; spec.runs];
    for (i, m) in manifests.iter().enumerate() {
        let path = dirs[i].join(MANIFEST);
        if let Some((field, mine, first)) = m.spec.difference(&spec) {
            return Err(crate::Error::invalid(
                format!("spec.{field}"),
                mine,
                format!(
                    "is not the experiment of {} ({field} = {first})",
                    first_dir.join(MANIFEST).display(),
                ),
            )
            .in_file(&path));
        }
        for &w in &m.workspaces {
            if let Some(j) = owner[w] {
                return Err(crate::Error::invalid(
                    "workspaces",
                    w,
                    format!("workspace {w} is also in {}", dirs[j].display()),
                )
                .in_file(&path));
            }
            owner[w] = Some(i);
        }
    }
    if let Some(w) = owner.iter().position(Option::is_none) {
        return Err(crate::Error::invalid(
            "DIR",
            match dirs.len() {
                1 => "1 folder".to_string(),
                n => format!("{n} folders"),
            },
            format!(
                "workspace {w} of {} is in none of them (a slice is missing)",
                spec.runs
            ),
        ));
    }
    let methods = methods(spec.preset);
    let mut records = Vec::with_capacity(spec.runs * methods.len());
    for (w, o) in owner.iter().enumerate() {
        let dir = dirs[o.expect("checked above")].join(format!("workspace{w}"));
        for (k, m) in methods.iter().enumerate() {
            let run_dir = dir.join(format!("method{k}"));
            let best = run_dir.join(super::runner::files::BEST);
            let text = crate::limits::read_text(&best, crate::limits::MAX_TEXT_FILE_BYTES)
                .map_err(|source| crate::Error::Read {
                    path: best.clone(),
                    source,
                })?;
            let mut summary: RunSummary =
                crate::strict::deserialize(&mut serde_json::Deserializer::from_str(&text))
                    .map_err(|e| crate::Error::Parse {
                        file: best.clone(),
                        message: e.to_string(),
                    })?;
            summary.check_figures().map_err(|e| e.in_file(&best))?;
            // The run of this workspace and method: a best.json of another method or
            // workspace put in its place would fill the row with another run's figures.
            let ws_seed = spec.seed.saturating_add(w as u64);
            for (field, value, expected) in [
                (
                    "optimizer",
                    summary.optimizer.clone(),
                    m.algorithm.name().to_string(),
                ),
                (
                    "checker",
                    summary.checker.clone(),
                    m.checker.name().to_string(),
                ),
                ("seed", summary.seed.to_string(), ws_seed.to_string()),
            ] {
                if value != expected {
                    return Err(crate::Error::invalid(
                        field,
                        value,
                        format!(
                            "workspace {w}, method {k} ({}) of the experiment has {expected}: the folder holds another run's results",
                            m.label
                        ),
                    )
                    .in_file(&best));
                }
            }
            if let Some(n) = spec.evaluations.filter(|&n| summary.evaluations > n) {
                return Err(crate::Error::invalid(
                    "evaluations",
                    summary.evaluations,
                    format!("the experiment makes at most {n} per run"),
                )
                .in_file(&best));
            }
            summary.elapsed_s = read_elapsed(&run_dir.join(super::runner::files::TIME))?;
            // The checkpoint's history is checked as it is read, and its content against its
            // checksum.
            let checkpoint = Runner::read_checkpoint(&run_dir)?;
            let checkpoint_path = run_dir.join(super::runner::files::CHECKPOINT);
            checkpoint.integrity.check(&checkpoint_path)?;
            if let Some(w) = checkpoint.integrity.warning(&checkpoint_path) {
                eprintln!("warning: {w}");
            }
            let history = checkpoint.history;
            records.push(RunRecord {
                workspace: w,
                method: k,
                summary,
                history,
            });
        }
    }
    std::fs::create_dir_all(out).map_err(|source| crate::Error::Write {
        path: out.to_path_buf(),
        source,
    })?;
    write_tables(&methods, &records, spec.time_limit, out)?;
    let manifest = Manifest {
        workspaces: (0..spec.runs).collect(),
        spec,
        shard: Shard::WHOLE,
    };
    write_atomic(
        &out.join(MANIFEST),
        serde_json::to_string_pretty(&manifest)
            .expect("a manifest serialises")
            .as_bytes(),
    )?;
    Ok(records)
}

fn write_tables(
    methods: &[Method],
    records: &[RunRecord],
    time_limit: f64,
    out: &Path,
) -> Result<()> {
    let mut runs_csv = String::from(
        "workspace,method,reachability,time_to_full_reach_s,cost,links_kept,joints_kept,evaluations,elapsed_s\n",
    );
    for r in records {
        runs_csv.push_str(&format!(
            "{},{},{},{},{},{},{},{},{:.3}\n",
            r.workspace,
            methods[r.method].label,
            r.summary.reachability,
            r.time_to_full_reach()
                .map_or(String::new(), |t| format!("{t:.3}")),
            r.summary.cost,
            r.summary.links_kept,
            r.summary.joints_kept,
            r.summary.evaluations,
            r.summary.elapsed_s
        ));
    }
    write_atomic(&out.join("runs.csv"), runs_csv.as_bytes())?;

    // Averaged curves on a grid of 100 instants; a run that has not finished its first
    // generation at `t` contributes R = 0 (nothing known yet).
    let grid: Vec<f64> = (0..=100).map(|i| time_limit * i as f64 / 100.0).collect();
    let metrics: [(&str, Metric); 4] = [
        ("reachability", |r| r.best_reachability),
        ("cost", |r| r.best_cost),
        ("links", |r| r.best_links as f64),
        ("joints", |r| r.best_joints as f64),
    ];
    let mut header = String::from("time_s");
    for m in methods {
        for (name, _) in &metrics {
            header.push_str(&format!(",{} {name}", m.label));
        }
    }
    let mut curves = format!("{header}\n");
    let mut mean_r: Vec<Vec<(f64, f64)>> = vec![Vec::new(); methods.len()];
    for &t in &grid {
        curves.push_str(&format!("{t:.3}"));
        for (k, _) in methods.iter().enumerate() {
            let runs: Vec<&RunRecord> = records.iter().filter(|r| r.method == k).collect();
            for (i, (_, f)) in metrics.iter().enumerate() {
                let values: Vec<f64> = runs
                    .iter()
                    .filter_map(|r| at(&r.history, t, *f).or((i == 0).then_some(0.0)))
                    .collect();
                let mean = if values.is_empty() {
                    f64::NAN
                } else {
                    values.iter().sum::<f64>() / values.len() as f64
                };
                if i == 0 {
                    mean_r[k].push((t, mean));
                }
                curves.push_str(&format!(",{mean}"));
            }
        }
        curves.push('\n');
    }
    write_atomic(&out.join("curves.csv"), curves.as_bytes())?;

    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (900, 520)).into_drawing_area();
        root.fill(&WHITE).expect("drawing on a string");
        let mut chart = ChartBuilder::on(&root)
            .caption("Average reachability against time", ("sans-serif", 22))
            .margin(14)
            .x_label_area_size(40)
            .y_label_area_size(56)
            .build_cartesian_2d(0.0..time_limit, 0.0..1.05)
            .expect("chart");
        chart
            .configure_mesh()
            .x_desc("time (s)")
            .y_desc("average best R")
            .draw()
            .expect("mesh");
        let colours = [BLUE, RED, GREEN, BLACK, MAGENTA, CYAN];
        for (k, m) in methods.iter().enumerate() {
            let colour = colours[k % colours.len()];
            chart
                .draw_series(LineSeries::new(mean_r[k].clone(), colour.stroke_width(2)))
                .expect("series")
                .label(m.label.clone())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], colour));
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .position(SeriesLabelPosition::LowerRight)
            .draw()
            .expect("legend");
        root.present().expect("present");
    }
    write_atomic(&out.join("curves.svg"), svg.as_bytes())
}

/// The `elapsed_s` of a run's `time.json`.
fn read_elapsed(path: &Path) -> Result<f64> {
    let text =
        crate::limits::read_text(path, crate::limits::MAX_TEXT_FILE_BYTES).map_err(|source| {
            crate::Error::Read {
                path: path.to_path_buf(),
                source,
            }
        })?;
    let v: serde_json::Value = serde_json::from_str(&text).map_err(|e| crate::Error::Parse {
        file: path.to_path_buf(),
        message: e.to_string(),
    })?;
    match v["elapsed_s"].as_f64() {
        Some(s) if (0.0..=crate::limits::MAX_SECONDS).contains(&s) => Ok(s),
        _ => Err(crate::Error::invalid(
            "elapsed_s",
            v["elapsed_s"].as_f64().map_or_else(
                || v["elapsed_s"].to_string(),
                |x| crate::error::Num(x).to_string(),
            ),
            format!(
                "must be a number of seconds from 0 to {}",
                crate::limits::MAX_SECONDS
            ),
        )
        .in_file(path)),
    }
}
