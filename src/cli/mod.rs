//! The commands of the `kinsynth` binary, one file each: parse the command's options, call the
//! library, print. `main.rs` only parses the command line and dispatches here.

/// `println!` that ends the process quietly when stdout is closed (e.g. piped into `head`).
macro_rules! say {
    ($($t:tt)*) => {{
        use std::io::Write as _;
        if writeln!(std::io::stdout(), $($t)*).is_err() {
            std::process::exit(0);
        }
    }};
}

pub mod check;
pub mod edges;
pub mod experiment;
mod islands;
pub mod merge;
pub mod optimize;
mod progress;
pub mod reach;
pub mod scenario;
pub mod urdf;

/// Applies `--checker` and `--lmax` to the scenario's planner settings (a given `L_max`
/// replaces any schedule).
pub fn override_planner(
    planner: &mut kinsynth::planning::PlannerConfig,
    checker: Option<kinsynth::collision::CheckerKind>,
    lmax: Option<f64>,
) -> Result<(), kinsynth::Error> {
    if let Some(c) = checker {
        planner.checker = c;
    }
    if let Some(l) = lmax {
        if !(l.is_finite() && l > 0.0) {
            return Err(kinsynth::Error::invalid(
                "--lmax",
                l,
                "must be positive and finite",
            ));
        }
        planner.l_max = l;
        planner.schedule = None;
    }
    Ok(())
}

/// A whole number given as `flag`: refused, naming the flag and the value, unless it is an
/// integer in `min..=max`.
pub fn whole(
    flag: &str,
    v: Option<f64>,
    min: u64,
    max: u64,
) -> Result<Option<u64>, kinsynth::Error> {
    match v {
        None => Ok(None),
        Some(x) if x.fract() == 0.0 && x >= min as f64 && x <= max as f64 => Ok(Some(x as u64)),
        Some(x) => Err(kinsynth::Error::invalid(
            flag,
            x,
            format!("must be a whole number from {min} to {max}"),
        )),
    }
}
