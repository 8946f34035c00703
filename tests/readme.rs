//! The README's examples are real: its scenario TOML validates, its design JSON loads, and its
//! two set-up commands are the ones CI runs.

use kinsynth::{Design, Scenario};
use std::path::Path;

fn readme() -> String {
    std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("README.md")).unwrap()
}

fn blocks(lang: &str) -> Vec<String> {
    let text = readme();
    let fence = format!("```{lang}\n");
    text.split(&fence)
        .skip(1)
        .map(|b| b.split("```").next().unwrap().to_string())
        .collect()
}

#[test]
fn scenario_example_is_valid() {
    let toml = blocks("toml");
    assert_eq!(toml.len(), 1);
    let spec = Scenario::parse(&toml[0]).unwrap();
    let s = Scenario::from_spec(&spec).unwrap();
    assert_eq!(s.space.template().links.len(), 8);
    assert_eq!(s.workspace.obstacles.len(), 1);
    assert_eq!(s.space.template().links[0].d, 0.3);
    // A point task, a full pose and an approach cone; a tool.
    let o = &s.workspace.orientations;
    assert_eq!(o.len(), 3);
    assert!(o[0].is_free());
    assert!(matches!(
        o[1],
        kinsynth::world::TaskOrientation::Pose { .. }
    ));
    assert!(matches!(
        o[2],
        kinsynth::world::TaskOrientation::Approach { .. }
    ));
    assert!(s.space.largest().chain().has_tool());
}

#[test]
fn design_example_loads() {
    let json = blocks("json");
    assert_eq!(json.len(), 1);
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("design.json");
    std::fs::write(&p, &json[0]).unwrap();
    let d = Design::load(&p).unwrap();
    assert_eq!(d.links.len(), 2);
    assert_eq!(d.chain().dof(), 1);
    // A best.json wraps the design.
    std::fs::write(&p, format!("{{\"design\": {}, \"cost\": 1.0}}", json[0])).unwrap();
    assert_eq!(Design::load(&p).unwrap(), d);
}

#[test]
fn setup_commands_are_the_ones_ci_runs() {
    let sh = blocks("sh");
    assert_eq!(sh.len(), 2, "exactly two set-up commands");
    assert!(sh[0].trim().starts_with("cargo run --release -- "));
    assert_eq!(sh[1].trim(), "cargo test");
    let ci =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join(".ci/run")).unwrap();
    assert!(ci.lines().any(|l| l.trim() == "cargo test"));
    // The main-job command optimises a bundled scenario that exists, with a budget under a
    // minute.
    assert!(sh[0].contains(" optimize "));
    let scenario = sh[0]
        .split_whitespace()
        .find(|w| w.ends_with(".toml"))
        .unwrap();
    let limit: f64 = sh[0]
        .split_whitespace()
        .skip_while(|w| *w != "--time-limit")
        .nth(1)
        .unwrap()
        .parse()
        .unwrap();
    assert!(limit < 60.0);
    assert!(Path::new(env!("CARGO_MANIFEST_DIR"))
        .join(scenario)
        .exists());
}

/// The README's "Limits" table gives the figures of `kinsynth::limits`.
#[test]
fn limits_table_matches_the_constants() {
    use kinsynth::limits::*;
    let text = readme();
    let grouped = |n: usize| {
        let digits = n.to_string();
        let mut out = String::new();
        for (i, c) in digits.chars().enumerate() {
            if i > 0 && (digits.len() - i) % 3 == 0 {
                out.push(',');
            }
            out.push(c);
        }
        out
    };
    let mib = |b: u64| format!("{} MiB", b >> 20);
    for row in [
        format!("| file size | {} | scenario TOML", mib(MAX_TEXT_FILE_BYTES)),
        format!(
            "| file size | {} | `checkpoint.json`",
            mib(MAX_CHECKPOINT_BYTES)
        ),
        format!("| file size | {} | mesh files", mib(MAX_MESH_FILE_BYTES)),
        format!("| XML nesting depth | {} |", MAX_XML_DEPTH),
        format!("| links | {} |", MAX_LINKS),
        format!(
            "| point colliders per link | {} |",
            grouped(MAX_COLLIDERS_PER_LINK)
        ),
        format!("| tasks | {} |", grouped(MAX_TASKS)),
        format!("| obstacles | {} |", grouped(MAX_OBSTACLES)),
        format!("per mesh file | {} |", grouped(MAX_MESH_TRIANGLES)),
        format!(
            "| mesh triangles per scenario | {} |",
            grouped(MAX_SCENE_MESH_TRIANGLES)
        ),
        format!(
            "| lengths and coordinates | ±{} m |",
            grouped(MAX_LENGTH as usize)
        ),
        format!("| angles | ±{} rad |", grouped(MAX_ANGLE as usize)),
        format!("| RRT iterations | {} |", grouped(MAX_ITERATIONS)),
        format!("| IK steps | {} |", grouped(MAX_IK_STEPS)),
        format!(
            "| population, GA tournament, ASA batch | {} |",
            grouped(MAX_POPULATION)
        ),
        format!("| other real settings | {:e} |", MAX_SETTING),
        format!("| file size | {} | COLLADA", mib(MAX_COLLADA_FILE_BYTES)),
        format!("| RRT tree nodes | {} |", grouped(MAX_TREE_NODES)),
        format!(
            "| path values per reach report | {} |",
            grouped(MAX_REPORT_PATH_VALUES)
        ),
        format!(
            "| file size | {} | reach reports",
            mib(MAX_REPORT_FILE_BYTES)
        ),
        format!(
            "| self-collision sampling work | {} |",
            grouped(MAX_SELF_COLLISION_WORK as usize)
        ),
        format!(
            "| body tests per planner run | {} |",
            grouped(MAX_BODY_TESTS as usize)
        ),
        format!(
            "| kinematics evaluations of the checker | {} per edge, {} per planner run |",
            grouped(kinsynth::collision::edge::certified::MAX_MIDPOINTS as usize),
            grouped(MAX_CHECK_FK as usize)
        ),
        format!(
            "| population × free variables | {} |",
            grouped(MAX_POPULATION_VARIABLES)
        ),
        format!(
            "| planner seeds | {} |",
            grouped(kinsynth::optimize::runner::MAX_SEEDS)
        ),
    ] {
        assert!(text.contains(&row), "README lacks `{row}`");
    }
}
