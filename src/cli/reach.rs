//! `kinsynth reach`: reachability of a design or of a URDF robot.

use super::{override_planner, whole};
use kinsynth::Scenario;
use std::path::PathBuf;

/// Reachability of a design: the share of task points an RRT from home reaches.
///
/// A best.json is replayed: without --seed, the planner seed, random stream and settings
/// of the evaluation that produced it give the same R and paths. Writes the report to
/// --json FILE and task_{i}.csv and task_{i}.json per reached task into --trajectories
/// DIR, when given; nothing otherwise.
#[derive(clap::Args)]
#[command(allow_negative_numbers = true)]
pub struct Args {
    /// The scenario file (TOML).
    pub file: PathBuf,
    /// A design JSON or an optimiser's best.json. Default: the scenario's largest design.
    #[arg(long)]
    pub design: Option<PathBuf>,
    /// Edge checker: discrete, segment, ccd or certified. Default: the scenario's.
    #[arg(long)]
    pub checker: Option<kinsynth::collision::CheckerKind>,
    /// Step bound L_max. Default: the scenario's.
    #[arg(long)]
    pub lmax: Option<f64>,
    /// Seed of the planner. Default: the scenario's (for a best.json: its own, replayed).
    #[arg(long)]
    pub seed: Option<u64>,
    /// Plan with N planner seeds (--seed and the N − 1 after it) and report the spread of
    /// R: min, mean and max. The report and trajectories are those of the first seed.
    #[arg(long)]
    pub seeds: Option<f64>,
    /// Write the report as JSON to this file (atomically).
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Put the planner's tree (each node's end effector and parent) into the --json report,
    /// for `kinsynth view` to draw.
    #[arg(long, requires = "json")]
    pub tree: bool,
    /// Write the SRDF of the self pairs this run checks (atomically): the allowed-collision
    /// matrix computed for the robot, with the pairs of --srdf for a URDF robot. With the URDF
    /// it lets MoveIt, or pinocchio and coal, check exactly the pairs kinsynth checked. The
    /// robot is named as in the --urdf file (MoveIt requires the same name), or for a design
    /// after the file, as `kinsynth urdf` names the URDF it exports.
    #[arg(long)]
    pub write_srdf: Option<PathBuf>,
    #[command(flatten)]
    pub urdf: UrdfReach,
}

/// Runs the command.
pub fn run(args: Args) -> Result<(), kinsynth::Error> {
    let Args {
        file,
        design,
        checker,
        lmax,
        seed,
        seeds,
        json,
        tree,
        write_srdf,
        urdf,
    } = args;
    use rayon::prelude::*;
    // Output locations are checked first: nothing is written when one of them is bad.
    if let Some(path) = &json {
        super::output_file(path)?;
    }
    if let Some(path) = &write_srdf {
        super::output_file(path)?;
        let same = |other: &Option<PathBuf>| {
            other
                .as_ref()
                .is_some_and(|o| kinsynth::io::same_place(o, path))
        };
        if same(&json) || same(&urdf.trajectories) {
            return Err(kinsynth::Error::invalid(
                "--write-srdf",
                path.display(),
                "is also the --json report or the --trajectories folder",
            ));
        }
    }
    if let Some(dir) = &urdf.trajectories {
        kinsynth::io::check_output_dir(dir)?;
        if json
            .as_ref()
            .is_some_and(|j| kinsynth::io::same_place(j, dir))
        {
            return Err(kinsynth::Error::invalid(
                "--trajectories",
                dir.display(),
                "is also the --json report",
            ));
        }
    }
    let s = Scenario::load(&file)?;
    // No output may replace a file the run reads.
    let inputs = super::inputs(
        &file,
        &s,
        &[
            (design.as_ref(), "the --design file"),
            (urdf.robot.urdf.as_ref(), "the --urdf robot"),
            (urdf.robot.srdf.as_ref(), "the --srdf file"),
        ],
    );
    if let Some(path) = &json {
        kinsynth::io::check_not_input("--json", path, &inputs)?;
    }
    if let Some(path) = &write_srdf {
        kinsynth::io::check_not_input("--write-srdf", path, &inputs)?;
    }
    if let Some(dir) = &urdf.trajectories {
        let files = (0..s.workspace.tasks.len())
            .flat_map(|i| kinsynth::export::trajectory::trajectory_files(dir, i));
        kinsynth::io::check_dir_not_input("--trajectories", dir, files, &inputs)?;
    }
    let max_seeds = kinsynth::optimize::runner::MAX_SEEDS as u64;
    let seeds = whole("--seeds", seeds, 1, max_seeds)?;
    // A best.json without --seed or --seeds replays the evaluation that produced it.
    let replay = match (&design, seed, seeds) {
        (Some(p), None, None) => kinsynth::optimize::runner::Replay::from_best(p)?,
        _ => None,
    };
    // `group`: the SRDF's planning group, an imported robot's own base and tip frames, and
    // its URDF robot name (none: the exported design's group, the robot named after the file).
    let (chain, urdf_names, body, group) = match urdf.robot.load(&s)? {
        Some(r) => {
            if let (Some(path), Some(why)) = (&write_srdf, r.srdf_cannot_name()) {
                // An SRDF names URDF links: it cannot be written for these bodies.
                return Err(kinsynth::Error::invalid(
                    "--write-srdf",
                    path.display(),
                    format!("an SRDF names the URDF's links, but {why}"),
                ));
            }
            urdf.robot.announce(&r);
            let body = std::sync::Arc::new(r.body);
            let group = Some((r.urdf.base, r.urdf.tip, r.urdf.robot));
            (r.urdf.chain, Some(r.urdf.joint_names), Some(body), group)
        }
        None => match &design {
            Some(p) => (kinsynth::Design::load(p)?.chain(), None, None, None),
            None => (s.space.largest().chain(), None, None, None),
        },
    };
    if let Some(dir) = &urdf.trajectories {
        // A file name in the folder taken by a folder fails here, before any work.
        kinsynth::export::trajectory::check_trajectory_files(dir, 0..s.workspace.tasks.len())?;
    }
    let mut planner = replay
        .as_ref()
        .map_or_else(|| s.planner.clone(), |r| r.planner.clone());
    override_planner(&mut planner, checker, lmax)?;
    let (first_seed, stream) = match &replay {
        Some(r) => {
            say!(
                "replaying the evaluation that produced {}: planner seed {}, stream {}",
                design
                    .as_ref()
                    .map_or(String::new(), |p| p.display().to_string()),
                r.seed,
                r.stream
            );
            (r.seed, r.stream)
        }
        None => (seed.unwrap_or(s.seed), 0),
    };
    let n = seeds.unwrap_or(1);
    let scene = std::sync::Arc::new(kinsynth::collision::CollisionScene::new(&s.workspace));
    let start = std::time::Instant::now();
    let mut reports: Vec<kinsynth::planning::ReachReport> = (0..n)
        .into_par_iter()
        .map(|k| {
            let seed = first_seed.wrapping_add(k);
            let plan = if tree && k == 0 {
                kinsynth::planning::reach::reachability_with_tree
            } else {
                kinsynth::planning::reachability_tasks
            };
            let mut report = plan(
                &chain,
                body.clone(),
                &scene,
                &s.workspace.tasks,
                &s.workspace.orientations,
                &planner,
                seed,
                stream,
            );
            if k > 0 {
                // Only the first seed's paths are shown and written.
                for t in &mut report.targets {
                    t.path = None;
                }
            }
            report
        })
        .collect();
    let elapsed = start.elapsed();
    let spread = (n > 1).then(|| {
        let r: Vec<f64> = reports.iter().map(|r| r.reachability).collect();
        let min = r.iter().copied().fold(f64::INFINITY, f64::min);
        let max = r.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let mean = r.iter().sum::<f64>() / r.len() as f64;
        for (k, rep) in reports.iter().enumerate() {
            say!(
                "seed {}: R = {:.3} ({} of {} tasks)",
                first_seed.wrapping_add(k as u64),
                rep.reachability,
                rep.reached(),
                rep.targets.len()
            );
        }
        say!(
            "R over {n} seeds ({}–{}): min {min:.3}, mean {mean:.3}, max {max:.3}",
            first_seed,
            first_seed.wrapping_add(n - 1)
        );
        serde_json::json!({
            "seeds": (0..n).map(|k| first_seed.wrapping_add(k)).collect::<Vec<_>>(),
            "reachability": r,
            "min": min,
            "mean": mean,
            "max": max,
        })
    });
    let mut report = reports.swap_remove(0);
    if let Some(names) = &urdf_names {
        kinsynth::import::urdf::rename_joints(&mut report, names);
    }
    say!(
        "R = {:.3} ({} of {} tasks) with {} at L_max {:.4}, seed {first_seed}{}: {} iterations, {} nodes, {} edge checks, {:.1} ms",
        report.reachability,
        report.reached(),
        report.targets.len(),
        report.checker,
        report.l_max,
        if stream == 0 { String::new() } else { format!(" stream {stream}") },
        report.iterations,
        report.nodes,
        report.edge_checks,
        elapsed.as_secs_f64() * 1e3
    );
    if let Some(why) = &report.home_blocked {
        say!("  {why}");
    }
    // A replay gives the R the best.json records, unless the file was changed since the run
    // wrote it (its design, say) or the planner is overridden.
    if let (Some(r), Some(p), None, None) = (
        replay.as_ref().and_then(|r| r.recorded),
        &design,
        checker,
        lmax,
    ) {
        if (r - report.reachability).abs() > 1e-9 {
            eprintln!(
                "warning: {}: records R = {}, and this replay of its evaluation gives {:.3}: the file is not as the run wrote it",
                p.display(),
                kinsynth::error::Num(r),
                report.reachability
            );
        }
    }
    for t in &report.targets {
        let angle = match (t.orientation_error, t.approach_error) {
            (Some(e), _) => format!("  orientation {:.2}°", e.to_degrees()),
            (_, Some(e)) => format!("  approach {:.2}°", e.to_degrees()),
            _ => String::new(),
        };
        say!(
            "  task {:>3} {:<11} error {:.4} m{angle}  path {}",
            t.index,
            if t.reached { "reached" } else { "not reached" },
            t.error,
            t.path.as_ref().map_or_else(
                || if t.path_omitted.is_some() {
                    "omitted"
                } else {
                    "-"
                }
                .to_string(),
                |p| format!("{} nodes", p.points.len())
            )
        );
        if let Some(why) = &t.path_omitted {
            say!("      path omitted: {why}");
        }
        if let Some(why) = &t.reason {
            if report.home_blocked.is_none() {
                say!("      {why}");
            }
        }
    }
    // Every output is staged, then all are put in place together: an error writing one
    // (a full disk, a device that refuses) leaves none written.
    let mut staged = kinsynth::io::Staged::default();
    if let Some(path) = &json {
        let mut v = report.to_json_value(stream);
        if let Some(spread) = spread {
            v["spread"] = spread;
        }
        let text = serde_json::to_string_pretty(&v).expect("a report serialises");
        staged.add(path, text.as_bytes())?;
    }
    let mut srdf_pairs = 0;
    if let Some(path) = &write_srdf {
        // The body the planner used: the imported one, else the one it builds from the
        // planner's self-collision settings.
        let built;
        let checked = match &body {
            Some(b) => &**b,
            None => {
                built = kinsynth::collision::RobotBody::capsules(&chain, &planner.self_collision);
                &built
            }
        };
        let name = group.as_ref().map(|(_, _, name)| name.as_str());
        let group = group
            .as_ref()
            .map(|(base, tip, _)| (base.as_str(), tip.as_str()));
        let text = kinsynth::export::srdf::body_srdf_text(checked, group, name, path);
        staged.add(path, text.as_bytes())?;
        srdf_pairs = checked.acm().disabled().len();
    }
    // A trajectories folder this run creates is removed again if the outputs fail.
    let created = urdf.trajectories.as_ref().filter(|d| !d.exists());
    let committed = (|| {
        let mut files = 0;
        if let Some(dir) = &urdf.trajectories {
            files =
                kinsynth::export::trajectory::stage_trajectories(&report, dir, &mut staged)?.len();
        }
        staged.commit()?;
        Ok::<_, kinsynth::Error>(files)
    })();
    if committed.is_err() {
        if let Some(dir) = created {
            let _ = std::fs::remove_dir(dir); // only if still empty
        }
    }
    let trajectory_files = committed?;
    if let Some(path) = &write_srdf {
        say!(
            "wrote {} ({srdf_pairs} pairs never checked)",
            path.display()
        );
    }
    if let Some(dir) = &urdf.trajectories {
        say!(
            "wrote {trajectory_files} trajectory files to {}",
            dir.display()
        );
    }
    Ok(())
}

/// `reach` options for evaluating an existing URDF robot and writing trajectories.
#[derive(clap::Args)]
pub struct UrdfReach {
    #[command(flatten)]
    pub robot: super::UrdfRobot,
    /// Write task_{index}.csv and task_{index}.json for every reached task into this directory.
    #[arg(long)]
    pub trajectories: Option<PathBuf>,
}
