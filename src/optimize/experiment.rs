//! The paper's experiments (§IV): several random workspaces, each optimised by several methods
//! under the same wall-clock budget; curves averaged over the workspaces, like Fig. 2 and 3.

use super::runner::{HistoryRow, Quiet, RunOptions, RunSummary, Runner};
use crate::collision::CheckerKind;
use crate::error::Result;
use crate::io::write_atomic;
use crate::scenario::preset::{self, Preset};
use crate::scenario::{Algorithm, Scenario};
use plotters::prelude::*;
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
    /// Plan as the paper's RRT does: from home alone, within the fixed iteration budget
    /// (`postures = 0`, `budget_growth = 1`); otherwise with the scenario's planner settings.
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

/// Runs the experiment: `runs` workspaces of `preset` (seeds `seed`, `seed + 1`, …), each
/// optimised by every method of [`methods`] for `time_limit` seconds (stopping early when
/// converged), writing into `out`: each workspace's scenario and run folders, `runs.csv` (one
/// line per run), `curves.csv` (averaged curves on a time grid) and `curves.svg`.
/// `log` receives a line per finished run.
pub fn run_experiment(
    preset: Preset,
    runs: usize,
    time_limit: f64,
    seed: u64,
    out: &Path,
    log: &mut dyn FnMut(&str),
) -> Result<Vec<RunRecord>> {
    let methods = methods(preset);
    let mut records = Vec::new();
    for w in 0..runs {
        let ws_seed = seed + w as u64;
        let spec = preset::generate(preset, ws_seed);
        let dir = out.join(format!("workspace{w}"));
        std::fs::create_dir_all(&dir).map_err(|source| crate::Error::Write {
            path: dir.clone(),
            source,
        })?;
        let scenario_path = dir.join("scenario.toml");
        write_atomic(&scenario_path, preset::to_toml(preset, &spec).as_bytes())?;
        let scenario = Scenario::load(&scenario_path)?;
        for (k, m) in methods.iter().enumerate() {
            let mut planner = scenario.planner.clone();
            planner.checker = m.checker;
            planner.l_max = m.l_max;
            planner.schedule = None;
            if m.paper_planner {
                planner.postures = 0;
                planner.budget_growth = 1;
            }
            let options = RunOptions {
                algorithm: m.algorithm,
                seed: ws_seed,
                time_limit: Some(time_limit),
                evaluations: None,
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
