//! `kinsynth view`: the browser report of a scenario, a robot and its reachability paths.

use kinsynth::export::view::{load_reach, write_report, RunView, ViewInput};
use kinsynth::Scenario;
use std::path::PathBuf;

/// Write the 3D report of a scenario and a robot as one self-contained HTML page.
///
/// Writes the file given by -o: obstacles as the checker sees them, the task points, the
/// robot's bodies and, with --reach, each reached task's path as an animation. It opens from
/// file:// with no network (three.js is inlined).
#[derive(clap::Args)]
pub struct Args {
    /// The scenario file (TOML).
    pub file: PathBuf,
    /// A design JSON or an optimiser's best.json (which adds the run's cost and settings).
    /// Default: the scenario's largest design.
    #[arg(long)]
    pub design: Option<PathBuf>,
    #[command(flatten)]
    pub robot: super::UrdfRobot,
    /// A reachability report (`kinsynth reach --json`, or a run's reach.json) of this robot
    /// in this scenario: its paths are animated.
    #[arg(long)]
    pub reach: Option<PathBuf>,
    /// Output HTML file (written atomically).
    #[arg(short, long)]
    pub output: PathBuf,
}

/// Runs the command.
pub fn run(args: Args) -> Result<(), kinsynth::Error> {
    let s = Scenario::load(&args.file)?;
    // The page must not replace a file it is made from.
    let inputs = super::inputs(
        &args.file,
        &s,
        &[
            (args.design.as_ref(), "the --design file"),
            (args.reach.as_ref(), "the --reach report"),
            (args.robot.urdf.as_ref(), "the --urdf robot"),
            (args.robot.srdf.as_ref(), "the --srdf file"),
        ],
    );
    super::output_file(&args.output)?;
    kinsynth::io::check_not_input("-o", &args.output, &inputs)?;
    let (chain, joint_names, body) = match args.robot.load(&s)? {
        Some(r) => {
            args.robot.announce(&r);
            (r.urdf.chain, Some(r.urdf.joint_names), r.body)
        }
        None => {
            let chain = match &args.design {
                Some(p) => kinsynth::Design::load(p)?.chain(),
                None => s.space.largest().chain(),
            };
            let body = kinsynth::collision::RobotBody::capsules(&chain, &s.planner.self_collision);
            (chain, None, body)
        }
    };
    let design = match (&args.robot.urdf, &args.design) {
        (Some(_), _) => None,
        (None, Some(p)) => Some(kinsynth::Design::load(p)?),
        (None, None) => Some(s.space.largest()),
    };
    // A best.json also carries the run's figures.
    // Its wall-clock time is in the time.json beside it, when there is one.
    let summary: Option<kinsynth::optimize::RunSummary> = args.design.as_ref().and_then(|p| {
        let text = kinsynth::limits::read_text(p, kinsynth::limits::MAX_TEXT_FILE_BYTES).ok()?;
        let mut summary: kinsynth::optimize::RunSummary =
            kinsynth::strict::deserialize(&mut serde_json::Deserializer::from_str(&text)).ok()?;
        let time = p.with_file_name(kinsynth::optimize::runner::files::TIME);
        if let Some(t) = kinsynth::limits::read_text(&time, kinsynth::limits::MAX_TEXT_FILE_BYTES)
            .ok()
            .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok())
        {
            summary.elapsed_s = t["elapsed_s"]
                .as_f64()
                .filter(|s| s.is_finite())
                .unwrap_or(0.0);
        }
        Some(summary)
    });
    // And its convergence plot is the convergence.svg beside it, when there is one (shown as
    // an image, which runs no script).
    let convergence = summary.as_ref().and(args.design.as_ref()).and_then(|p| {
        let svg = p.with_file_name(kinsynth::optimize::runner::files::PLOT);
        let text = kinsynth::limits::read_text(&svg, kinsynth::limits::MAX_TEXT_FILE_BYTES).ok()?;
        let start = text.trim_start();
        (start.starts_with("<svg") || start.starts_with("<?xml")).then_some(text)
    });
    let report = match &args.reach {
        Some(p) => Some(load_reach(p, &s.workspace.tasks, chain.dof())?),
        None => None,
    };
    let title = format!(
        "{} — {}",
        s.name,
        match (&args.robot.urdf, &args.design) {
            (Some(p), _) | (None, Some(p)) => p.display().to_string(),
            (None, None) => "largest design".to_string(),
        }
    );
    let input = ViewInput {
        title,
        workspace: &s.workspace,
        chain: &chain,
        body: &body,
        joint_names,
        design: design.as_ref(),
        report: report.as_ref(),
        run: summary.as_ref().map(|summary| RunView {
            summary,
            history: &[],
            convergence_svg: convergence.as_deref(),
        }),
    };
    write_report(&input, &args.output)?;
    let triangles: usize = s
        .workspace
        .obstacles
        .iter()
        .map(|o| o.mesh_triangles())
        .sum();
    say!(
        "wrote {} ({} obstacles, {} tasks, {} of them with a path; {} links, {} bodies{})",
        args.output.display(),
        s.workspace.obstacles.len(),
        s.workspace.tasks.len(),
        report.as_ref().map_or(0, |r| r
            .targets
            .iter()
            .filter(|t| t.reached && t.path.is_some())
            .count()),
        chain.link_count(),
        body.len(),
        if triangles > 0 {
            format!(", {triangles} mesh triangles")
        } else {
            String::new()
        }
    );
    Ok(())
}
