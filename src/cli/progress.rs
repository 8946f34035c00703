//! The progress bar of `kinsynth optimize` (indicatif, on stderr, or on stdout when only
//! stdout is a terminal, as under `mpirun`; hidden when neither is a terminal or with
//! `--quiet`). An island job adds a line per island below the bar.
use indicatif::{MultiProgress, ProgressBar, ProgressDrawTarget, ProgressStyle};
use kinsynth::optimize::islands::IslandRow;
use kinsynth::optimize::runner::{HistoryRow, Observer, RunOptions};
use std::io::IsTerminal;

pub struct Bar {
    multi: MultiProgress,
    bar: ProgressBar,
    islands: Vec<ProgressBar>,
    by_evaluations: bool,
}

impl Bar {
    pub fn new(options: &RunOptions, quiet: bool) -> Self {
        let (len, by_evaluations) = match (options.evaluations, options.time_limit) {
            (Some(n), _) => (n, true),
            (None, Some(t)) => ((t * 10.0) as u64, false),
            (None, None) => (0, false),
        };
        let target = if quiet {
            ProgressDrawTarget::hidden()
        } else if std::io::stderr().is_terminal() || !std::io::stdout().is_terminal() {
            ProgressDrawTarget::stderr()
        } else {
            ProgressDrawTarget::stdout()
        };
        let multi = MultiProgress::with_draw_target(target);
        let bar = multi.add(ProgressBar::new(len));
        bar.set_style(
            ProgressStyle::with_template("{elapsed_precise} [{bar:30}] {percent:>3}% {msg}")
                .expect("valid template")
                .progress_chars("=> "),
        );
        Bar {
            multi,
            bar,
            islands: Vec::new(),
            by_evaluations,
        }
    }
}

impl Observer for Bar {
    fn generation(&mut self, row: &HistoryRow) {
        let rate = if row.elapsed_s > 0.0 {
            row.evaluations as f64 / row.elapsed_s
        } else {
            0.0
        };
        self.bar.set_position(if self.by_evaluations {
            row.evaluations
        } else {
            (row.elapsed_s * 10.0) as u64
        });
        self.bar.set_message(format!(
            "{} evals ({rate:.0}/s)  best cost {:.4}  best R {:.2}",
            row.evaluations, row.best_cost, row.best_reachability
        ));
    }
    fn islands(&mut self, rows: &[IslandRow]) {
        while self.islands.len() < rows.len() {
            let line = self.multi.add(ProgressBar::new_spinner());
            line.set_style(ProgressStyle::with_template("  {msg}").expect("valid template"));
            self.islands.push(line);
        }
        for (line, r) in self.islands.iter().zip(rows) {
            line.set_message(format!(
                "island {:>3}: {} evals  best cost {:.4}  best R {:.2}",
                r.island, r.evaluations, r.best_cost, r.best_reachability
            ));
        }
    }
    fn finish(&mut self) {
        for line in &self.islands {
            line.finish_and_clear();
        }
        self.bar.finish_and_clear();
    }
}
