//! The commands of the `kinsynth` binary, one file each: parse the command's options, call the
//! library, print. `main.rs` only parses the command line and dispatches here.

use std::path::{Path, PathBuf};

/// `println!` for a command's messages. When an output file of the command is the standard
/// output ([`output_file`], e.g. `--json /dev/stdout`), they go to stderr instead, so that
/// the file's bytes come through alone. Once stdout is closed (its reader, such as `head`, has
/// ended) nothing more is printed, and the command still writes its files.
macro_rules! say {
    ($($t:tt)*) => {{
        use std::io::Write as _;
        use std::sync::atomic::Ordering;
        if $crate::cli::STDOUT_TAKEN.load(Ordering::Relaxed) {
            eprintln!($($t)*);
        } else if !$crate::cli::STDOUT_CLOSED.load(Ordering::Relaxed)
            && writeln!(std::io::stdout(), $($t)*).is_err()
        {
            $crate::cli::STDOUT_CLOSED.store(true, Ordering::Relaxed);
        }
    }};
}

/// Set when an output file of the command is the standard output (see `say!`).
pub static STDOUT_TAKEN: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Set once a message could not be written to stdout (see `say!`).
pub static STDOUT_CLOSED: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Checks, before any work, that `path` can take an output file
/// ([`kinsynth::io::check_output_file`]); when it is the standard output (`/dev/stdout`,
/// `/proc/self/fd/1`, or a file stdout is redirected to), the command's messages go to stderr
/// from now on.
pub fn output_file(path: &Path) -> Result<(), kinsynth::Error> {
    kinsynth::io::check_output_file(path)?;
    // A device (a terminal, /dev/null) shared with stdout keeps the messages where they were:
    // only a pipe or a file would mix them into the output's bytes.
    let stdout = Path::new("/dev/stdout");
    let shared = std::fs::metadata(stdout).is_ok_and(|m| {
        #[cfg(unix)]
        {
            use std::os::unix::fs::FileTypeExt;
            !m.file_type().is_char_device()
        }
        #[cfg(not(unix))]
        {
            let _ = m;
            true
        }
    });
    if shared && kinsynth::io::same_file(path, stdout) {
        STDOUT_TAKEN.store(true, std::sync::atomic::Ordering::Relaxed);
    }
    Ok(())
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
pub mod view;

/// The input files of a command, each with what it is, for the checks that no output replaces
/// one ([`kinsynth::io::check_not_input`]): the scenario `file`, the mesh files of `s` and the
/// given files of `more`.
pub fn inputs<'a>(
    file: &'a Path,
    s: &'a kinsynth::Scenario,
    more: &[(Option<&'a PathBuf>, &'a str)],
) -> Vec<(&'a Path, &'a str)> {
    let mut all = vec![(file, "the input scenario")];
    all.extend(
        more.iter()
            .filter_map(|(p, what)| p.map(|p| (p.as_path(), *what))),
    );
    all.extend(
        s.mesh_files()
            .into_iter()
            .map(|m| (m, "a mesh of the scenario")),
    );
    all
}

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
        planner.l_max = checked_lmax(l)?;
        planner.schedule = None;
    }
    Ok(())
}

/// A step bound given as `--lmax`: refused, naming the flag and the value, unless it is
/// positive and at most [`kinsynth::limits::MAX_SETTING`], as a scenario's `planner.l_max`.
pub fn checked_lmax(l: f64) -> Result<f64, kinsynth::Error> {
    use kinsynth::limits::{within, MAX_SETTING};
    if l > 0.0 && within(l, MAX_SETTING) {
        Ok(l)
    } else {
        Err(kinsynth::Error::invalid(
            "--lmax",
            kinsynth::error::Num(l),
            format!("must be positive and at most {MAX_SETTING}"),
        ))
    }
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
        // Read as a number so that `2.5` or `-1` get this message too; one beyond 2^53 is
        // not exact any more, and is written in exponent form rather than as false digits.
        Some(x) => Err(kinsynth::Error::invalid(
            flag,
            kinsynth::error::Num(x),
            format!("must be a whole number from {min} to {max}"),
        )),
    }
}

/// Options for a robot read from a URDF file instead of a design (`reach`, `view`).
#[derive(clap::Args)]
pub struct UrdfRobot {
    /// Evaluate this URDF robot instead of a design (see the README's "URDF" section).
    #[arg(long, conflicts_with = "design")]
    pub urdf: Option<PathBuf>,
    /// URDF link where the chain starts. Default: the root link.
    #[arg(long, requires = "urdf")]
    pub base_frame: Option<String>,
    /// URDF link whose origin is the end effector. Default: the leaf below the base.
    #[arg(long, requires = "urdf")]
    pub tip_frame: Option<String>,
    /// Capsule radius of the URDF robot's links (m). Default: the largest radius of its
    /// collision cylinders, capsules and spheres, else 0.05.
    #[arg(long, requires = "urdf")]
    pub radius: Option<f64>,
    /// Bodies of the URDF robot's links: `collision` (their <collision> meshes, boxes,
    /// cylinders, spheres and capsules) or `capsules` (capsules between joint origins).
    #[arg(long, requires = "urdf", default_value_t = kinsynth::import::BodyChoice::Collision)]
    pub body: kinsynth::import::BodyChoice,
    /// Where `package://NAME/…` mesh URIs point: NAME=DIR (repeatable). Default: a folder
    /// NAME above the URDF.
    #[arg(long, requires = "urdf", value_parser = package_arg)]
    pub package: Vec<(String, PathBuf)>,
    /// An SRDF whose <disable_collisions> link pairs are never checked for self-collision.
    #[arg(long, requires = "urdf")]
    pub srdf: Option<PathBuf>,
}

impl UrdfRobot {
    /// The URDF robot of `--urdf` with its body, for the scenario `s` (its point colliders and
    /// self-collision settings), or `None` without `--urdf`. Its note, if any, is for
    /// [`UrdfRobot::announce`] once the command has checked what it needs of the robot.
    pub fn load(
        &self,
        s: &kinsynth::Scenario,
    ) -> Result<Option<kinsynth::import::ImportedRobot>, kinsynth::Error> {
        let Some(p) = &self.urdf else {
            return Ok(None);
        };
        let options = kinsynth::import::ImportOptions {
            body: self.body,
            packages: self.package.clone(),
            srdf: self.srdf.clone(),
            self_collision: s.planner.self_collision.clone(),
        };
        let r = kinsynth::import::load_robot(
            p,
            self.base_frame.as_deref(),
            self.tip_frame.as_deref(),
            self.radius,
            s.space.template().colliders_per_link,
            &options,
        )?;
        Ok(Some(r))
    }

    /// Prints the note of the import of `r` to stderr, if it has one (after the command's own
    /// checks, so that an error stays alone on its line).
    pub fn announce(&self, r: &kinsynth::import::ImportedRobot) {
        if let (Some(p), Some(note)) = (&self.urdf, &r.note) {
            eprintln!("note: {}: {note}", p.display());
        }
        let acm = r.body.acm();
        if let (Some(p), true) = (&self.urdf, acm.work_limited()) {
            eprintln!(
                "note: {}: the self-collision sampling stopped after {} random configurations, \
                 at its work limit of {}: the pairs it had not decided stay checked (an SRDF or \
                 allowed_collisions can leave them out)",
                p.display(),
                acm.samples_taken(),
                kinsynth::limits::MAX_SELF_COLLISION_WORK
            );
        }
    }
}

/// Parses `--package NAME=DIR`.
fn package_arg(s: &str) -> Result<(String, PathBuf), String> {
    match s.split_once('=') {
        Some((n, d)) if !n.is_empty() && !d.is_empty() => Ok((n.to_string(), PathBuf::from(d))),
        _ => Err(format!("`{s}`: expected NAME=DIR")),
    }
}
