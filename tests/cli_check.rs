//! `kinsynth check` and `kinsynth scenario` through the command line: every validation rule
//! fails with a non-zero exit code and a one-line message naming file, field and value.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const BIN: &str = env!("CARGO_BIN_EXE_kinsynth");

const VALID: &str = r#"
clearance = 0.01

[robot]
links = 3
link_radius = 0.02
uniform = { a = [0.0, 0.4], axes = { ry = { min = [-3.0, 0.0], max = [0.0, 3.0] } } }

[[obstacle]]
name = "drum"
shape = "sphere"
position = [0.6, 0.0, 0.8]
radius = 0.2

[[obstacle]]
shape = "cuboid"
position = [-0.6, 0.0, 0.0]
size = [0.2, 0.2, 0.2]

[[task]]
point = [0.5, 0.0, 0.3]

[[task]]
point = [0.0, 0.0, 0.9]
"#;

fn write(dir: &Path, text: &str) -> PathBuf {
    let p = dir.join("scenario.toml");
    std::fs::write(&p, text).unwrap();
    p
}

fn check(path: &Path) -> Output {
    Command::new(BIN).arg("check").arg(path).output().unwrap()
}

/// Runs `check` on `text`, expects failure, and returns the error line.
fn rejected(text: &str) -> String {
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), text);
    let out = check(&p);
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert!(!out.status.success(), "accepted:\n{text}");
    assert_eq!(out.status.code(), Some(1));
    assert_eq!(
        stderr.lines().count(),
        1,
        "one-line error expected: {stderr}"
    );
    assert!(
        stderr.starts_with("error: ") && stderr.contains(&p.display().to_string()),
        "error must name the file: {stderr}"
    );
    stderr
}

fn assert_mentions(msg: &str, parts: &[&str]) {
    for p in parts {
        assert!(msg.contains(p), "`{p}` missing from: {msg}");
    }
}

#[test]
fn valid_scenario_passes_with_a_summary() {
    let dir = tempfile::tempdir().unwrap();
    let out = check(&write(dir.path(), VALID));
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8(out.stdout).unwrap();
    assert_mentions(
        &stdout,
        &[
            "links           3",
            "free variables  9",
            "obstacles       2",
            "tasks           2",
        ],
    );
    assert!(out.stderr.is_empty(), "no warning expected");
}

#[test]
fn negative_zero_and_nan_radius() {
    let m = rejected(&VALID.replace("radius = 0.2", "radius = -0.2"));
    assert_mentions(&m, &["obstacle[0].radius", "-0.2", "positive"]);
    let m = rejected(&VALID.replace("radius = 0.2", "radius = 0.0"));
    assert_mentions(&m, &["obstacle[0].radius = 0", "positive"]);
    let m = rejected(&VALID.replace("radius = 0.2", "radius = nan"));
    assert_mentions(&m, &["obstacle[0].radius = NaN"]);
}

#[test]
fn bad_cuboid_size() {
    let m = rejected(&VALID.replace("size = [0.2, 0.2, 0.2]", "size = [0.2, -0.1, 0.2]"));
    assert_mentions(&m, &["obstacle[1].size", "-0.1"]);
}

#[test]
fn cylinder_and_capsule_dimensions() {
    let cyl = VALID.replace("shape = \"sphere\"", "shape = \"cylinder\"\nlength = -1.0");
    let m = rejected(&cyl);
    assert_mentions(&m, &["obstacle[0].length = -1", "positive"]);
    let cap = VALID.replace("shape = \"sphere\"", "shape = \"capsule\"");
    let m = rejected(&cap);
    assert_mentions(
        &m,
        &["obstacle[0].length", "missing", "capsule needs `length`"],
    );
    let m = rejected(&VALID.replace("radius = 0.2", "radius = 0.2\nsize = [1.0, 1.0, 1.0]"));
    assert_mentions(&m, &["obstacle[0].size", "a sphere has no `size`"]);
}

#[test]
fn non_finite_position_and_task() {
    let m = rejected(&VALID.replace("position = [0.6, 0.0, 0.8]", "position = [0.6, inf, 0.8]"));
    assert_mentions(&m, &["obstacle[0].position", "inf"]);
    let m = rejected(&VALID.replace("point = [0.5, 0.0, 0.3]", "point = [nan, 0.0, 0.3]"));
    assert_mentions(&m, &["task[0].point", "NaN"]);
}

#[test]
fn task_inside_obstacle_names_both() {
    let m = rejected(&VALID.replace("point = [0.0, 0.0, 0.9]", "point = [0.6, 0.0, 0.75]"));
    assert_mentions(&m, &["task[1]", "[0.6, 0, 0.75]", "obstacle[0]", "drum"]);
}

#[test]
fn fixed_range_min_above_max() {
    let text = VALID.replace(
        "ry = { min = [-3.0, 0.0], max = [0.0, 3.0] }",
        "ry = { min = 1.0, max = -1.0 }",
    );
    let m = rejected(&text);
    assert_mentions(
        &m,
        &[
            "robot.uniform.axes.ry",
            "min = 1",
            "max = -1",
            "min must not exceed max",
        ],
    );
}

#[test]
fn free_bounds_reversed_or_infinite() {
    let m = rejected(&VALID.replace("a = [0.0, 0.4]", "a = [0.5, 0.1]"));
    assert_mentions(
        &m,
        &[
            "robot.uniform.a",
            "[0.5, 0.1]",
            "lower bound exceeds upper bound",
        ],
    );
    let m = rejected(&VALID.replace("a = [0.0, 0.4]", "a = [0.0, inf]"));
    assert_mentions(&m, &["robot.uniform.a", "[0, inf]", "finite"]);
    let m = rejected(&VALID.replace("max = [0.0, 3.0]", "max = [0.0, nan]"));
    assert_mentions(&m, &["robot.uniform.axes.ry.max", "NaN"]);
}

#[test]
fn robot_section_values() {
    let m = rejected(&VALID.replace("links = 3", "links = 0"));
    assert_mentions(&m, &["robot.links = 0", "at least 1"]);
    let m = rejected(&VALID.replace("link_radius = 0.02", "link_radius = -0.02"));
    assert_mentions(&m, &["robot.link_radius = -0.02"]);
    let m = rejected(&format!("{VALID}\n[[robot.link]]\nindex = 4\na = 0.1\n"));
    assert_mentions(&m, &["robot.link[0].index = 4", "1..=3"]);
}

#[test]
fn settings_sections() {
    let m = rejected(&VALID.replace("clearance = 0.01", "clearance = -0.01"));
    assert_mentions(&m, &["clearance = -0.01"]);
    let m = rejected(&format!("{VALID}\n[planner]\nl_max = 0.0\n"));
    assert_mentions(&m, &["planner.l_max = 0", "positive"]);
    let m = rejected(&format!("{VALID}\n[planner]\ngoal_bias = 1.5\n"));
    assert_mentions(&m, &["planner.goal_bias = 1.5"]);
    let m = rejected(&format!("{VALID}\n[planner]\nchecker = \"magic\"\n"));
    assert_mentions(&m, &["planner.checker", "magic"]);
    let m = rejected(&format!("{VALID}\n[planner]\nik_hold_limits = 3\n"));
    assert_mentions(&m, &["planner.ik_hold_limits", "boolean", "line "]);
    let m = rejected(&format!("{VALID}\n[planner]\naimed_steering = \"yes\"\n"));
    assert_mentions(&m, &["planner.aimed_steering", "boolean"]);
    let m = rejected(&format!("{VALID}\n[objective]\nlambda3 = -1.0\n"));
    assert_mentions(&m, &["objective.lambda3 = -1"]);
    let m = rejected(&format!("{VALID}\n[optimizer]\npopulation = 1\n"));
    assert_mentions(&m, &["optimizer.population = 1"]);
}

#[test]
fn unknown_and_missing_keys() {
    let m = rejected(&VALID.replace("radius = 0.2", "radus = 0.2"));
    assert_mentions(&m, &["obstacle[0]", "radus", "line "]);
    let m = rejected(&VALID.replace("links = 3\n", ""));
    assert_mentions(&m, &["robot", "links"]);
    let m = rejected(&VALID.replace("uniform = {", "uniform = { rw = 1.0,"));
    assert_mentions(&m, &["robot.uniform", "rw"]);
    let m = rejected(&VALID.replace("[robot]", "[robt]"));
    assert_mentions(&m, &["robt"]);
    let m = rejected(&VALID.replace("max = [0.0, 3.0] } } }", "max = [0.0, 3.0] } }"));
    assert_mentions(&m, &["line 9, column 1", "inline table"]);
}

#[test]
fn no_task_points() {
    let text = VALID.split("[[task]]").next().unwrap().to_string();
    let m = rejected(&text);
    assert_mentions(&m, &["task", "at least one task"]);
}

#[test]
fn unreadable_file() {
    let out = check(Path::new("/nonexistent/scenario.toml"));
    assert_eq!(out.status.code(), Some(1));
    let m = String::from_utf8(out.stderr).unwrap();
    assert_mentions(&m, &["/nonexistent/scenario.toml", "cannot read"]);
}

#[test]
fn home_pose_contact_is_a_warning_naming_link_and_obstacle() {
    // A ball on the stretched arm's path: link 2 spans x ∈ [0.4, 0.8] at home; links 1 and 3
    // stay 0.03 m away from it, more than the clearance.
    let text = VALID.replace("position = [0.6, 0.0, 0.8]", "position = [0.6, 0.0, -0.15]");
    let dir = tempfile::tempdir().unwrap();
    let out = check(&write(dir.path(), &text));
    assert!(out.status.success());
    let m = String::from_utf8(out.stderr).unwrap();
    assert_mentions(&m, &["warning", "link 2", "obstacle[0] (drum)"]);
    assert_eq!(m.lines().count(), 1, "only link 2 touches: {m}");
}

#[test]
fn presets_are_reproducible_and_valid() {
    let dir = tempfile::tempdir().unwrap();
    for preset in ["paper-2d", "paper-3d"] {
        let mut files = Vec::new();
        for name in ["a.toml", "b.toml"] {
            let p = dir.path().join(format!("{preset}-{name}"));
            let out = Command::new(BIN)
                .args(["scenario", "--preset", preset, "--seed", "7", "-o"])
                .arg(&p)
                .output()
                .unwrap();
            assert!(out.status.success());
            files.push(std::fs::read(&p).unwrap());
            let out = check(&p);
            assert!(
                out.status.success(),
                "{}",
                String::from_utf8_lossy(&out.stderr)
            );
            assert!(out.stderr.is_empty(), "home pose must be clear");
        }
        assert_eq!(files[0], files[1], "{preset}: same seed, same bytes");
    }
    let out = Command::new(BIN)
        .args(["scenario", "--preset", "paper-4d", "-o", "x.toml"])
        .output()
        .unwrap();
    assert!(!out.status.success());
}

#[test]
fn bundled_scenarios_check() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/scenarios");
    let mut n = 0;
    for entry in std::fs::read_dir(dir).unwrap() {
        let p = entry.unwrap().path();
        if p.extension().is_some_and(|e| e == "toml") {
            let out = check(&p);
            assert!(
                out.status.success(),
                "{}: {}",
                p.display(),
                String::from_utf8_lossy(&out.stderr)
            );
            n += 1;
        }
    }
    assert!(n >= 2);
}

#[test]
fn help_lists_every_subcommand() {
    let out = Command::new(BIN).arg("--help").output().unwrap();
    let s = String::from_utf8(out.stdout).unwrap();
    for cmd in ["scenario", "check"] {
        assert!(s.lines().any(|l| l.trim_start().starts_with(cmd)), "{s}");
    }
}
