//! What a run produces, apart from the runner that produces it: the history rows, the run's
//! summary (`best.json`) and the names of the files in its output directory. The exports
//! (`export::plot`, `export::view`) read these types; the runner writes them.

use super::islands::Migration;
use super::objective::Breakdown;
use crate::Design;
use serde::{Deserialize, Serialize};

/// One row of `history.csv`: the state after a generation.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct HistoryRow {
    /// Seconds since the run started (summed over resumed sessions).
    pub elapsed_s: f64,
    /// Evaluations so far.
    pub evaluations: u64,
    /// Best cost so far.
    pub best_cost: f64,
    /// Reachability of the best design so far.
    pub best_reachability: f64,
    /// Links kept by the best design so far.
    pub best_links: usize,
    /// Joints kept by the best design so far.
    pub best_joints: usize,
}

/// One row of `islands.csv`: an island after a generation and its migration.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct IslandRow {
    /// Generation (from 1).
    pub generation: u64,
    /// Island index (from 0).
    pub island: usize,
    /// Evaluations of this island so far.
    pub evaluations: u64,
    /// The island's best cost so far (a migrant counts once it has arrived).
    pub best_cost: f64,
    /// Reachability of that design.
    pub best_reachability: f64,
}

/// Most rows a run keeps of `history.csv`, and of `islands.csv`, in its checkpoint and its
/// outputs: a row is about 130 bytes of `checkpoint.json`, so a run of fast generations
/// (paper-2d makes about 30 a second) would outgrow the checkpoint's read limit
/// ([`crate::limits::MAX_CHECKPOINT_BYTES`]) after about 4.7 hours. Beyond it the rows are
/// thinned ([`thin_history`], [`thin_island_rows`]).
pub const MAX_HISTORY_ROWS: usize = 100_000;

/// Keeps `history` within [`MAX_HISTORY_ROWS`] once a row has been added: when it is over,
/// every other row that repeats its predecessor's best (cost, `R`, links and joints; only the
/// time and evaluations move on) is dropped, so that every change of the best keeps its first
/// row; should that leave more than three quarters, every other row of the older half goes
/// too, but for the rows where `R` changes (so the time to `R = 1` stays exact), unless those
/// alone are too many. The first and last rows always stay. The same rows in give the same
/// rows out, so a resumed run keeps what an uninterrupted one keeps.
pub fn thin_history(history: &mut Vec<HistoryRow>) {
    if history.len() <= MAX_HISTORY_ROWS {
        return;
    }
    let same = |a: &HistoryRow, b: &HistoryRow| {
        a.best_cost.to_bits() == b.best_cost.to_bits()
            && a.best_reachability.to_bits() == b.best_reachability.to_bits()
            && a.best_links == b.best_links
            && a.best_joints == b.best_joints
    };
    let last = history.len() - 1;
    let mut repeat = 0usize;
    let mut keep = vec![true; history.len()];
    for i in 1..last {
        if same(&history[i], &history[i - 1]) {
            keep[i] = repeat % 2 == 1;
            repeat += 1;
        }
    }
    let mut i = 0;
    history.retain(|_| {
        i += 1;
        keep[i - 1]
    });
    // Still over three quarters: every other row of the older half goes, but for those where
    // the best's R changes (the first row of R = 1 among them); and if those alone keep it
    // over, every other row of the older half.
    for keep_changes_of_r in [true, false] {
        if history.len() <= MAX_HISTORY_ROWS / 2 + MAX_HISTORY_ROWS / 4 {
            return;
        }
        let half = history.len() / 2;
        let changes: Vec<bool> = (0..history.len())
            .map(|k| {
                k > 0
                    && history[k].best_reachability.to_bits()
                        != history[k - 1].best_reachability.to_bits()
            })
            .collect();
        let mut i = 0;
        history.retain(|_| {
            let k = i;
            i += 1;
            k >= half || k % 2 == 0 || (keep_changes_of_r && changes[k])
        });
    }
}

/// Keeps the rows of `islands.csv` within [`MAX_HISTORY_ROWS`] once a generation's rows have
/// been added: when they are over, every other generation kept in the older half of the rows
/// goes, whole (the first generation kept stays, as does the newer half). The same rows in
/// give the same rows out.
pub fn thin_island_rows(rows: &mut Vec<IslandRow>) {
    if rows.len() <= MAX_HISTORY_ROWS {
        return;
    }
    let half = rows.len() / 2;
    let mut group = 0usize;
    let mut keep = vec![true; rows.len()];
    for i in 1..half {
        if rows[i].generation != rows[i - 1].generation {
            group += 1;
        }
        // Within the older half, and the generation does not run on past it.
        keep[i] = group % 2 == 0 || rows[i].generation == rows[half].generation;
    }
    let mut i = 0;
    rows.retain(|_| {
        i += 1;
        keep[i - 1]
    });
}

/// Where an island job's results came from, as `best.json` records it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct IslandsInfo {
    /// Number of islands.
    pub islands: usize,
    /// Migration settings.
    pub migration: Migration,
    /// The island whose best design was the job's best before the final re-check.
    pub best_island: usize,
}

/// How `R` of a run's result held when re-checked with fresh planner seeds.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RobustReachability {
    /// Planner seeds (random streams) of the re-check.
    pub seeds: usize,
    /// Stream of the first of them (the others follow) with the run's seed.
    pub first_stream: u64,
    /// Lowest `R` over the seeds: the robust figure the result is chosen by.
    pub min: f64,
    /// Mean `R`.
    pub mean: f64,
    /// Highest `R`.
    pub max: f64,
    /// `R` for each seed.
    pub values: Vec<f64>,
    /// Distinct final candidates re-checked: those that could be chosen (see the runner's
    /// re-check), usually 1.
    pub candidates: usize,
}

/// The result of a run: the best design and how it was found.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct RunSummary {
    /// The best design.
    pub design: Design,
    /// Its cost (paper Eq. 23).
    pub cost: f64,
    /// Its reachability.
    pub reachability: f64,
    /// Links with a body.
    pub links_kept: usize,
    /// Axes with a non-zero range.
    pub joints_kept: usize,
    /// Evaluations made.
    pub evaluations: u64,
    /// Generations made.
    pub generations: u64,
    /// Seconds spent. Wall-clock time is not fixed by the seed, so it is written to
    /// `time.json` ([`files::TIME`]), not to `best.json`: two runs with the same seed write the
    /// same `best.json`, byte for byte.
    #[serde(skip)]
    pub elapsed_s: f64,
    /// Seed.
    pub seed: u64,
    /// Optimiser name.
    pub optimizer: String,
    /// Edge checker name.
    pub checker: String,
    /// `L_max` used (at the end of any schedule).
    pub l_max: f64,
    /// Why the run stopped.
    pub stopped: String,
    /// The terms of the objective for the best design.
    pub breakdown: Breakdown,
    /// Random stream (with the planner seed `seed`) of the planner run that produced
    /// `reachability`: `kinsynth reach --design best.json` replays it.
    pub stream: u64,
    /// Planner settings of that run (after overrides and any schedule).
    pub planner: crate::planning::PlannerConfig,
    /// `R` of the result re-checked with fresh planner seeds (absent when the re-check is off).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub robust_reachability: Option<RobustReachability>,
    /// The cost of Eq. 23 with the lowest re-checked `R`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub robust_cost: Option<f64>,
    /// The islands of an island job (absent for one population).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub islands: Option<IslandsInfo>,
    /// Seconds the final re-check took (included in `elapsed_s`; not written to `best.json`).
    #[serde(skip)]
    pub recheck_s: f64,
}

/// Names of the files a run writes into its output directory.
pub mod files {
    /// The best design and its figures.
    pub const BEST: &str = "best.json";
    /// The run's wall-clock seconds (`elapsed_s`, `recheck_s`), kept apart from `best.json`.
    pub const TIME: &str = "time.json";
    /// One row per generation.
    pub const HISTORY: &str = "history.csv";
    /// The reachability report of the best design.
    pub const REACH: &str = "reach.json";
    /// Best R and best cost against time.
    pub const PLOT: &str = "convergence.svg";
    /// The state for `--resume`.
    pub const CHECKPOINT: &str = "checkpoint.json";
    /// The best design as a URDF robot.
    pub const URDF: &str = "robot.urdf";
    /// Its SRDF: planning group and allowed-collision matrix.
    pub const SRDF: &str = "robot.srdf";
    /// The browser report: the scene, the best design and its paths in 3D, with the run's
    /// convergence, cost breakdown and settings.
    pub const REPORT: &str = "report.html";
    /// One row per island per generation (island jobs only).
    pub const ISLANDS: &str = "islands.csv";
    /// Folder of the joint trajectories of the best design, one pair of files per reached task.
    pub const TRAJECTORIES: &str = "trajectories";
}

/// A reachability must lie in [0, 1].
fn check_reachability(field: &str, r: f64) -> crate::Result<()> {
    if (0.0..=1.0).contains(&r) {
        Ok(())
    } else {
        Err(crate::Error::invalid(
            field,
            crate::error::Num(r),
            "must lie in [0, 1]",
        ))
    }
}

/// A cost (paper Eq. 23, whose weights are not negative) must be finite and not negative.
fn check_cost(field: &str, c: f64) -> crate::Result<()> {
    if c.is_finite() && c >= 0.0 {
        Ok(())
    } else {
        Err(crate::Error::invalid(
            field,
            crate::error::Num(c),
            "must be finite and not negative",
        ))
    }
}

/// A count of links or joints kept must be at most `max` (`what`: why).
fn check_kept(field: &str, n: usize, max: usize, what: &str) -> crate::Result<()> {
    if n <= max {
        Ok(())
    } else {
        Err(crate::Error::invalid(
            field,
            n,
            format!("must be at most {max} ({what})"),
        ))
    }
}

/// Checks a run's history as a checkpoint holds it: per row, seconds from 0 to
/// [`crate::limits::MAX_SECONDS`], `R` in [0, 1], a finite cost ≥ 0 and counts a design of
/// at most [`crate::limits::MAX_LINKS`] links can have. Errors name the row's field
/// (`history[3].best_cost`) and the value.
pub fn check_history(history: &[HistoryRow]) -> crate::Result<()> {
    use crate::limits::{MAX_LINKS, MAX_SECONDS};
    for (i, row) in history.iter().enumerate() {
        let field = |f: &str| format!("history[{i}].{f}");
        if !(0.0..=MAX_SECONDS).contains(&row.elapsed_s) {
            return Err(crate::Error::invalid(
                field("elapsed_s"),
                crate::error::Num(row.elapsed_s),
                format!("must be a number of seconds from 0 to {MAX_SECONDS}"),
            ));
        }
        check_reachability(&field("best_reachability"), row.best_reachability)?;
        check_cost(&field("best_cost"), row.best_cost)?;
        let limit = format!("{MAX_LINKS} links");
        check_kept(&field("best_links"), row.best_links, MAX_LINKS, &limit)?;
        check_kept(
            &field("best_joints"),
            row.best_joints,
            6 * MAX_LINKS,
            &limit,
        )?;
    }
    Ok(())
}

impl RunSummary {
    /// Checks the figures of a `best.json`: its design, `R` in [0, 1], a finite cost ≥ 0, and
    /// links and joints kept that the design can have (six axes a link) and has. Errors name the
    /// field (`design.links[2].a`, `cost`) and the value.
    pub fn check_figures(&self) -> crate::Result<()> {
        self.design.validate().map_err(|e| e.under("design"))?;
        check_reachability("reachability", self.reachability)?;
        check_cost("cost", self.cost)?;
        let links = self.design.links.len();
        let what = format!("{links} links");
        check_kept("links_kept", self.links_kept, links, &what)?;
        check_kept("joints_kept", self.joints_kept, 6 * links, &what)?;
        // And they are the design's own.
        for (field, value, kept, what) in [
            (
                "links_kept",
                self.links_kept,
                self.design.links_kept(),
                "links",
            ),
            (
                "joints_kept",
                self.joints_kept,
                self.design.joints_kept(),
                "joints",
            ),
        ] {
            if value != kept {
                return Err(crate::Error::invalid(
                    field,
                    value,
                    format!("the design keeps {kept} {what}"),
                ));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(i: u64, cost: f64, r: f64) -> HistoryRow {
        HistoryRow {
            elapsed_s: i as f64 * 0.03,
            evaluations: 32 * i,
            best_cost: cost,
            best_reachability: r,
            best_links: 3,
            best_joints: 4,
        }
    }

    /// 300,000 generations whose best changes every 7,919th (and reaches R = 1 at 123,457):
    /// the history stays within the limit, keeps its first and last rows and the first row of
    /// every change of the best, in order.
    #[test]
    fn the_history_is_thinned_keeping_every_change() {
        let mut history = Vec::new();
        let mut changes = Vec::new();
        let (mut cost, mut r) = (100.0, 0.5);
        for i in 0..300_000u64 {
            if i % 7_919 == 0 || i == 123_457 {
                cost -= 0.001;
                changes.push(i);
            }
            if i == 123_457 {
                r = 1.0;
            }
            history.push(row(i, cost, r));
            thin_history(&mut history);
            assert!(history.len() <= MAX_HISTORY_ROWS, "{i}: {}", history.len());
        }
        assert!(history.len() > MAX_HISTORY_ROWS / 2, "{}", history.len());
        assert_eq!(history[0].evaluations, 0);
        assert_eq!(history.last().unwrap().evaluations, 32 * 299_999);
        let kept: Vec<u64> = history.iter().map(|h| h.evaluations / 32).collect();
        assert!(kept.windows(2).all(|w| w[0] < w[1]));
        for c in changes {
            assert!(kept.binary_search(&c).is_ok(), "change at {c} dropped");
        }
        let first_full = history.iter().find(|h| h.best_reachability == 1.0).unwrap();
        assert_eq!(first_full.evaluations, 32 * 123_457);
        // The best changes at 4 generations of 5 (too many changes to keep them all), and R
        // reaches 1 at 40,001: that row stays.
        let mut history = Vec::new();
        let mut cost = 1e6;
        for i in 0..200_000u64 {
            if i % 5 != 0 {
                cost -= 1.0;
            }
            let r = if i >= 40_001 { 1.0 } else { 0.5 };
            history.push(row(i, cost, r));
            thin_history(&mut history);
            assert!(history.len() <= MAX_HISTORY_ROWS);
        }
        let first_full = history.iter().find(|h| h.best_reachability == 1.0).unwrap();
        assert_eq!(first_full.evaluations, 32 * 40_001);
        // Every row a change: halved by position in the older half, first and last kept.
        let mut history: Vec<HistoryRow> = (0..=MAX_HISTORY_ROWS as u64)
            .map(|i| row(i, 1e6 - i as f64, 0.5))
            .collect();
        thin_history(&mut history);
        assert!(
            history.len() <= MAX_HISTORY_ROWS * 3 / 4 + 1,
            "{}",
            history.len()
        );
        assert_eq!(history[0].evaluations, 0);
        assert_eq!(
            history.last().unwrap().evaluations,
            32 * MAX_HISTORY_ROWS as u64
        );
    }

    /// Three islands over 100,000 generations: `islands.csv` stays near the limit, and every
    /// generation it keeps has all its islands' rows.
    #[test]
    fn island_rows_are_thinned_by_whole_generations() {
        let mut rows = Vec::new();
        for g in 1..=100_000u64 {
            for island in 0..3 {
                rows.push(IslandRow {
                    generation: g,
                    island,
                    evaluations: g * 10,
                    best_cost: 1.0,
                    best_reachability: 1.0,
                });
            }
            thin_island_rows(&mut rows);
            assert!(rows.len() <= MAX_HISTORY_ROWS + 3, "{g}: {}", rows.len());
        }
        assert!(rows.len() > MAX_HISTORY_ROWS / 2);
        assert_eq!(rows[0].generation, 1);
        assert_eq!(rows.last().unwrap().generation, 100_000);
        for chunk in rows.chunks(3) {
            assert!(chunk.iter().all(|r| r.generation == chunk[0].generation));
            let islands: Vec<usize> = chunk.iter().map(|r| r.island).collect();
            assert_eq!(islands, [0, 1, 2]);
        }
    }
}
