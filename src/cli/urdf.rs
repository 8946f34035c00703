//! `kinsynth urdf`: exports a design as URDF and SRDF.

use kinsynth::Scenario;
use std::path::PathBuf;

/// Export a design (design JSON or best.json) as a URDF robot and its SRDF.
///
/// Writes the file given by -o and, beside it, the same name with the extension .srdf
/// (planning group and allowed-collision matrix), or the file given by --srdf.
#[derive(clap::Args)]
pub struct Args {
    /// The design JSON, or an optimiser's best.json.
    pub design: PathBuf,
    /// Output URDF file (written atomically); the robot is named after its stem (when it is a
    /// device or a pipe such as /dev/stdout: after the --srdf file's stem, else `robot`), in
    /// the URDF and in the SRDF alike.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Output SRDF file. Default: beside the URDF, its name with the extension .srdf; none
    /// when -o is not a regular file (a device or a pipe such as /dev/stdout).
    #[arg(long)]
    pub srdf: Option<PathBuf>,
    /// Scenario whose [robot] self-collision settings (self_collision, allowed_collisions,
    /// self_collision_samples, seed) fill the SRDF. Default: self-collision on, 1000
    /// samples, seed 0.
    #[arg(long)]
    pub scenario: Option<PathBuf>,
}

/// Runs the command.
pub fn run(args: Args) -> Result<(), kinsynth::Error> {
    let Args {
        design,
        output,
        srdf,
        scenario,
    } = args;
    let d = kinsynth::Design::load(&design)?;
    let s = scenario.as_ref().map(|p| Scenario::load(p)).transpose()?;
    let config = s
        .as_ref()
        .map_or_else(Default::default, |s| s.planner.self_collision.clone());
    // Beside a regular file only: `/dev/null.srdf` or `/dev/stdout.srdf` is no place for it.
    // A standard stream redirected to a file is a regular file reached through /proc
    // (`/dev/stdout` → `/proc/self/fd/1`): no SRDF beside that either. Other files under /dev
    // (`/dev/shm/robot.urdf`) get theirs.
    let written = std::path::absolute(&output).unwrap_or_else(|_| output.clone());
    let through_proc = written.starts_with("/proc")
        || std::fs::read_link(&written).is_ok_and(|t| t.starts_with("/proc"));
    let special = std::fs::metadata(&output).is_ok_and(|m| !m.is_file() && !m.is_dir())
        || through_proc
        || kinsynth::io::same_file(&output, std::path::Path::new("/dev/stdout"));
    let given = srdf.is_some();
    let srdf = srdf.or_else(|| (!special).then(|| output.with_extension("srdf")));
    // The same file however spelt (`-o o.urdf --srdf ./o.urdf`).
    if srdf
        .as_deref()
        .is_some_and(|p| kinsynth::io::same_place(p, &output))
    {
        return Err(kinsynth::Error::invalid(
            "-o",
            output.display(),
            if given {
                "is also --srdf"
            } else {
                "the URDF must not end in .srdf (the SRDF is written beside it under that name)"
            },
        ));
    }
    // Both locations are checked before anything is written, so that no URDF is left without
    // its SRDF.
    super::output_file(&output)?;
    if let Some(srdf) = &srdf {
        super::output_file(srdf)?;
    }
    // Neither may replace a file the export is made from.
    let mut inputs = vec![(design.as_path(), "the input design")];
    if let (Some(p), Some(s)) = (&scenario, &s) {
        inputs = super::inputs(p, s, &[]);
        inputs.insert(0, (design.as_path(), "the input design"));
    }
    kinsynth::io::check_not_input("-o", &output, &inputs)?;
    if let Some(srdf) = &srdf {
        if let Err(kinsynth::Error::InvalidValue { reason, .. }) =
            kinsynth::io::check_not_input("--srdf", srdf, &inputs)
        {
            return Err(if given {
                kinsynth::Error::invalid("--srdf", srdf.display(), reason)
            } else {
                kinsynth::Error::invalid(
                    "-o",
                    output.display(),
                    format!("the SRDF beside it, {}, {reason}", srdf.display()),
                )
            });
        }
    }
    // Both files are staged, then put in place together: an error writing one (a full disk,
    // a device that refuses) leaves neither written.
    // One robot name for both (MoveIt refuses an SRDF that names another robot than its
    // URDF): the URDF file's stem, else (the URDF goes to a device or a pipe) the SRDF file's,
    // else `robot`.
    let stem = |p: &std::path::Path| {
        p.file_stem()
            .and_then(|s| s.to_str())
            .filter(|s| !s.is_empty())
            .map(str::to_string)
    };
    let name = if special { None } else { stem(&output) }
        .or_else(|| srdf.as_deref().and_then(stem))
        .unwrap_or_else(|| "robot".to_string());
    let mut staged = kinsynth::io::Staged::default();
    let text = kinsynth::export::urdf::design_to_urdf_string(&d, &name);
    staged.add(&output, text.as_bytes())?;
    let body = kinsynth::collision::RobotBody::capsules(&d.chain(), &config);
    if let Some(srdf) = &srdf {
        let text = kinsynth::export::srdf::body_srdf_text(&body, None, Some(&name), srdf);
        staged.add(srdf, text.as_bytes())?;
    }
    staged.commit()?;
    // A design folded through itself at home is exported as it is (its SRDF keeps the crossing
    // pair enabled), but it cannot start any motion: say so.
    if let Some((a, b)) = body.acm().home_fold() {
        eprintln!(
            "warning: {}: the home pose self-collides: the bodies of link {a} and link {b} cross each other (the SRDF keeps the pair enabled; reachability is 0)",
            design.display()
        );
    }
    // Counted as `optimize` reports a design: links with a length and axes with a range
    // (paper Eq. 28–29); the URDF has a frame for every link of the chain.
    let and = srdf.map_or_else(
        || "; no SRDF (-o is not a regular file: give --srdf FILE for one)".to_string(),
        |p| format!(" and {}", p.display()),
    );
    say!(
        "wrote {} ({} links kept of {}, {} joints kept){and}",
        output.display(),
        d.links_kept(),
        d.links.len(),
        d.joints_kept(),
    );
    Ok(())
}
