//! The progress bar of `kinsynth optimize` (indicatif, on stderr; hidden when stderr is
//! not a terminal or with `--quiet`).
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use kinsynth::optimize::runner::{HistoryRow, Observer, RunOptions};

pub struct Bar {
    bar: ProgressBar,
    by_evaluations: bool,
}

impl Bar {
    pub fn new(options: &RunOptions, quiet: bool) -> Self {
        let (len, by_evaluations) = match (options.evaluations, options.time_limit) {
            (Some(n), _) => (n, true),
            (None, Some(t)) => ((t * 10.0) as u64, false),
            (None, None) => (0, false),
        };
        let bar = ProgressBar::new(len);
        if quiet {
            bar.set_draw_target(ProgressDrawTarget::hidden());
        }
        bar.set_style(
            ProgressStyle::with_template("{elapsed_precise} [{bar:30}] {percent:>3}% {msg}")
                .expect("valid template")
                .progress_chars("=> "),
        );
        Bar {
            bar,
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
    fn finish(&mut self) {
        self.bar.finish_and_clear();
    }
}
