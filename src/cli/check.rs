//! `kinsynth check`: validates a scenario and prints a summary.

use kinsynth::Scenario;
use std::path::PathBuf;

/// Validate a scenario file and print a short summary.
///
/// Writes no files.
#[derive(clap::Args)]
pub struct Args {
    /// The scenario file (TOML).
    pub file: PathBuf,
}

/// Runs the command.
pub fn run(args: Args) -> Result<(), kinsynth::Error> {
    let Args { file } = args;
    let s = Scenario::load(&file)?;
    let largest = s.space.largest();
    let chain = largest.chain();
    say!("{}: ok", file.display());
    say!("  name            {}", s.name);
    say!(
        "  links           {} (largest design: {} joints, reach {:.3} m)",
        largest.links.len(),
        chain.dof(),
        largest.total_length()
    );
    say!("  free variables  {}", s.space.dim());
    say!("  obstacles       {}", s.workspace.obstacles.len());
    let oriented = |approach: bool| {
        s.workspace
            .orientations
            .iter()
            .filter(|o| match o {
                kinsynth::world::TaskOrientation::Approach { .. } => approach,
                kinsynth::world::TaskOrientation::Pose { .. } => !approach,
                kinsynth::world::TaskOrientation::Free => false,
            })
            .count()
    };
    let (cones, poses) = (oriented(true), oriented(false));
    if cones + poses == 0 {
        say!("  tasks           {}", s.workspace.tasks.len());
    } else {
        say!(
            "  tasks           {} ({poses} with an orientation, {cones} with an approach cone)",
            s.workspace.tasks.len()
        );
    }
    if let Some(t) = &largest.tool {
        say!(
            "  tool            position {:?}, rpy {:?} in the last frame",
            t.position,
            t.rpy
        );
    }
    say!("  clearance       {} m", s.workspace.clearance);
    say!(
        "  planner         {} checker, l_max {:.4}, {} iterations",
        s.planner.checker.name(),
        s.planner.l_max,
        s.planner.max_iterations
    );
    for c in s.home_contacts() {
        let o = &s.workspace.obstacles[c.obstacle];
        eprintln!(
            "warning: {}: the largest design's home pose has link {} touching obstacle[{}] ({}): distance {:.4} m, clearance {} m",
            file.display(),
            c.link,
            c.obstacle,
            o.name,
            c.distance,
            s.workspace.clearance
        );
    }
    Ok(())
}
