//! Hostile and careless inputs through the command line: devices, FIFOs, huge files, deep XML,
//! absurd sizes and magnitudes, vectors of the wrong length. Each gets exit code 1 and a
//! one-line error naming the file, the field and the value: never a panic (exit 101), an
//! abort, a hang or gigabytes of memory.

use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

const BIN: &str = env!("CARGO_BIN_EXE_kinsynth");

fn repo(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

/// Runs the binary (killed after 60 s) and returns its exit code and stderr.
fn run(args: &[&OsStr]) -> (Option<i32>, String) {
    let mut child = Command::new(BIN)
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if start.elapsed() > Duration::from_secs(60) {
            let _ = child.kill();
            let _ = child.wait();
            panic!("no exit within 60 s: {args:?}");
        }
        std::thread::sleep(Duration::from_millis(10));
    };
    let mut stderr = String::new();
    use std::io::Read;
    child
        .stderr
        .take()
        .unwrap()
        .read_to_string(&mut stderr)
        .unwrap();
    (status.code(), stderr)
}

/// `view` of the scenario `cell` with the URDF robot `urdf` succeeds (its page in `dir`).
fn view_reads(cell: &Path, urdf: &Path, dir: &Path) {
    let (code, stderr) = run(&[
        "view".as_ref(),
        cell.as_os_str(),
        "--urdf".as_ref(),
        urdf.as_os_str(),
        "-o".as_ref(),
        dir.join("v.html").as_os_str(),
    ]);
    assert_eq!(code, Some(0), "{stderr}");
}

/// The command must fail with exit code 1 and one line `error: …` that contains every part.
fn rejected(args: &[&OsStr], parts: &[&str]) -> String {
    let (code, stderr) = run(args);
    assert_eq!(code, Some(1), "exit code (101 is a panic): {stderr}");
    assert_eq!(
        stderr.lines().count(),
        1,
        "one-line error expected: {stderr}"
    );
    assert!(stderr.starts_with("error: "), "{stderr}");
    for p in parts {
        assert!(stderr.contains(p), "`{p}` missing from: {stderr}");
    }
    stderr
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

const ROBOT: &str =
    "[robot]\nlinks = 2\nuniform = { a = [0.0, 0.4], axes = { ry = { min = -3.0, max = 3.0 } } }\n";
const TASK: &str = "\n[[task]]\npoint = [0.5, 0.0, 0.3]\n";

fn check(path: &Path) -> Vec<&OsStr> {
    vec!["check".as_ref(), path.as_os_str()]
}

#[cfg(unix)]
#[test]
fn dev_zero_as_any_input_file_is_refused() {
    let zero = Path::new("/dev/zero");
    let s = zero.to_str().unwrap();
    rejected(&check(zero), &[s, "not a regular file", "character device"]);
    rejected(
        &[
            "urdf".as_ref(),
            zero.as_os_str(),
            "-o".as_ref(),
            "x.urdf".as_ref(),
        ],
        &[s, "character device"],
    );
    let cell = repo("examples/scenarios/ur5-cell.toml");
    rejected(
        &[
            "reach".as_ref(),
            cell.as_os_str(),
            "--urdf".as_ref(),
            zero.as_os_str(),
        ],
        &[s, "character device"],
    );
    rejected(
        &[
            "reach".as_ref(),
            cell.as_os_str(),
            "--design".as_ref(),
            zero.as_os_str(),
        ],
        &[s, "character device"],
    );
    // A checkpoint that is a link to /dev/zero.
    let dir = tempfile::tempdir().unwrap();
    let cp = dir.path().join("checkpoint.json");
    std::os::unix::fs::symlink(zero, &cp).unwrap();
    rejected(
        &[
            "optimize".as_ref(),
            "--resume".as_ref(),
            dir.path().as_os_str(),
        ],
        &[cp.to_str().unwrap(), "character device"],
    );
}

#[cfg(unix)]
#[test]
fn mesh_path_linked_to_dev_zero_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = dir.path().join("zero.stl");
    std::os::unix::fs::symlink("/dev/zero", &mesh).unwrap();
    let p = write(
        dir.path(),
        "s.toml",
        &format!(
            "{ROBOT}\n[[obstacle]]\nshape = \"mesh\"\nfile = \"zero.stl\"\nposition = [2.0, 0.0, 0.0]\n{TASK}"
        ),
    );
    rejected(
        &check(&p),
        &["obstacle[0].file", "zero.stl", "character device"],
    );
}

#[cfg(unix)]
#[test]
fn fifo_as_mesh_or_scenario_does_not_block() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("pipe.stl");
    let made = Command::new("mkfifo").arg(&fifo).status().unwrap();
    assert!(made.success());
    let p = write(
        dir.path(),
        "s.toml",
        &format!(
            "{ROBOT}\n[[obstacle]]\nshape = \"mesh\"\nfile = \"pipe.stl\"\nposition = [2.0, 0.0, 0.0]\n{TASK}"
        ),
    );
    let start = Instant::now();
    rejected(&check(&p), &["obstacle[0].file", "pipe.stl", "a FIFO"]);
    rejected(&check(&fifo), &["pipe.stl", "a FIFO"]);
    assert!(start.elapsed() < Duration::from_secs(20));
}

#[test]
fn directory_as_scenario_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    rejected(&check(dir.path()), &["a directory"]);
}

#[test]
fn oversized_scenario_file_is_refused_without_reading_it() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("big.toml");
    // A sparse file of 1 GiB: refused by its size, not read.
    std::fs::File::create(&p).unwrap().set_len(1 << 30).unwrap();
    rejected(
        &check(&p),
        &["big.toml", "1073741824 bytes", "limit of 16777216"],
    );
}

#[test]
fn absurd_link_and_collider_counts_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    for (text, parts) in [
        (
            ROBOT.replace("links = 2", "links = 1000000000"),
            ["robot.links", "1000000000", "at most 64"],
        ),
        (
            ROBOT.replace("links = 2", "links = 10000"),
            ["robot.links", "10000", "at most 64"],
        ),
        (
            ROBOT.replace("links = 2", "links = 2\ncolliders_per_link = 1000000000"),
            ["robot.colliders_per_link", "1000000000", "at most 1000"],
        ),
    ] {
        let p = write(dir.path(), "s.toml", &format!("{text}{TASK}"));
        let mut all = vec![p.to_str().unwrap()];
        all.extend(parts);
        rejected(&check(&p), &all);
    }
}

#[test]
fn too_many_tasks_or_obstacles_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let tasks = "\n[[task]]\npoint = [0.5, 0.0, 0.3]\n".repeat(10_001);
    let p = write(dir.path(), "tasks.toml", &format!("{ROBOT}{tasks}"));
    rejected(&check(&p), &["tasks.toml", "task = 10001", "at most 10000"]);
    let obstacles =
        "\n[[obstacle]]\nshape = \"sphere\"\nposition = [5, 0, 0]\nradius = 0.1\n".repeat(100_001);
    let p = write(
        dir.path(),
        "obst.toml",
        &format!("{ROBOT}{obstacles}{TASK}"),
    );
    rejected(
        &check(&p),
        &["obst.toml", "obstacle = 100001", "at most 100000"],
    );
}

#[test]
fn vectors_must_have_exactly_three_elements() {
    let dir = tempfile::tempdir().unwrap();
    let sphere = "\n[[obstacle]]\nshape = \"sphere\"\nposition = [2.0, 0.0, 0.0]\nradius = 0.1\n";
    for (text, field) in [
        (
            format!("{ROBOT}{}{TASK}", sphere.replace("[2.0, 0.0, 0.0]", "[2.0, 0.0, 0.0, 7.0]")),
            "obstacle[0].position",
        ),
        (
            format!("{ROBOT}{sphere}{}", TASK.replace("[0.5, 0.0, 0.3]", "[0.5, 0.0, 0.3, 1.0]")),
            "task[0].point",
        ),
        (
            format!("{ROBOT}{}{TASK}", sphere.replace("radius = 0.1", "radius = 0.1\nrpy = [0, 0, 0, 0]")),
            "obstacle[0].rpy",
        ),
        (
            format!(
                "{ROBOT}\n[[obstacle]]\nshape = \"cuboid\"\nposition = [2, 0, 0]\nsize = [1, 1]\n{TASK}"
            ),
            "obstacle[0].size",
        ),
        (
            format!("{}{TASK}", ROBOT.replace("links = 2", "links = 2\nbase = { position = [0, 0, 0, 0] }")),
            "robot.base.position",
        ),
    ] {
        let p = write(dir.path(), "s.toml", &text);
        let e = rejected(&check(&p), &[p.to_str().unwrap(), field]);
        assert!(e.contains("invalid length"), "{e}");
    }
    // The same in a design.
    let d = write(
        dir.path(),
        "d.json",
        r#"{"base": {"position": [0, 0, 0, 1]}, "link_radius": 0.02, "colliders_per_link": 4,
            "links": [{"a": 0.3, "axes": {"ry": [-1, 1]}}]}"#,
    );
    rejected(
        &[
            "urdf".as_ref(),
            d.as_os_str(),
            "-o".as_ref(),
            dir.path().join("x.urdf").as_os_str(),
        ],
        &["d.json", "base.position", "invalid length"],
    );
}

fn design(a: &str, ry: &str, links: usize) -> String {
    let link = format!(r#"{{"a": {a}, "axes": {{"ry": {ry}}}}}"#);
    format!(
        r#"{{"link_radius": 0.02, "colliders_per_link": 4, "links": [{}]}}"#,
        vec![link; links].join(", ")
    )
}

#[test]
fn huge_design_values_are_refused_naming_field_and_value() {
    let dir = tempfile::tempdir().unwrap();
    let cell = repo("examples/scenarios/paper-2d.toml");
    for (text, parts) in [
        (
            design("1e308", "[-1, 1]", 2),
            vec!["links[0].a", "1e308", "1000 m"],
        ),
        (
            design("0.3", "[-1e308, 1e308]", 2),
            vec!["links[0].axes.ry", "1e308", "1000 rad"],
        ),
        (
            design("0.3", "[-1, 1]", 10_000),
            vec!["links", "10000 links", "at most 64"],
        ),
        // Inside a best.json, the field is named from the file's top, as a wrong type is.
        (
            format!(
                r#"{{"cost": 1, "design": {}}}"#,
                design("1e308", "[-1, 1]", 2)
            ),
            vec!["d.json: design.links[0].a = 1e308", "1000 m"],
        ),
        (
            format!(
                r#"{{"cost": 1, "design": {}}}"#,
                design("\"x\"", "[-1, 1]", 2)
            ),
            vec!["d.json: design.links[0].a: invalid type"],
        ),
    ] {
        let p = write(dir.path(), "d.json", &text);
        let mut all = vec![p.to_str().unwrap()];
        all.extend(parts);
        rejected(
            &[
                "reach".as_ref(),
                cell.as_os_str(),
                "--design".as_ref(),
                p.as_os_str(),
            ],
            &all,
        );
    }
}

#[test]
fn huge_scenario_values_are_refused_naming_field_and_value() {
    let dir = tempfile::tempdir().unwrap();
    for (text, parts) in [
        (
            ROBOT.replace("[0.0, 0.4]", "[0.0, 1e308]"),
            vec!["robot.uniform.a", "1e308", "1000 m"],
        ),
        (
            ROBOT.replace("min = -3.0", "min = -1e308"),
            vec!["robot.uniform.axes.ry.min", "-1e308", "1000 rad"],
        ),
    ] {
        let p = write(dir.path(), "s.toml", &format!("{text}{TASK}"));
        let mut all = vec![p.to_str().unwrap()];
        all.extend(parts);
        rejected(&check(&p), &all);
    }
    let p = write(
        dir.path(),
        "s.toml",
        &format!("{ROBOT}\n[planner]\nmax_iterations = 1000000000\n{TASK}"),
    );
    rejected(&check(&p), &["planner.max_iterations", "1000000000"]);
    // The iteration limit is 100,000: the nearest-node scan makes a run's time grow with the
    // square of its iterations.
    at_the_limit(
        dir.path(),
        100_000,
        |n| format!("{ROBOT}\n[planner]\nmax_iterations = {n}\n{TASK}"),
        &["planner.max_iterations", "100001", "1..=100000"],
    );
}

/// The scenario `text(limit)` passes `check` and `text(limit + 1)` fails it with one line that
/// contains `parts`.
fn at_the_limit(dir: &Path, limit: usize, text: impl Fn(usize) -> String, parts: &[&str]) {
    let p = write(dir, "s.toml", &text(limit));
    let (code, stderr) = run(&check(&p));
    assert_eq!(code, Some(0), "{stderr}");
    let p = write(dir, "s.toml", &text(limit + 1));
    rejected(&check(&p), parts);
}

#[test]
fn urdf_joint_limits_of_1e308_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let ur5 = std::fs::read_to_string(repo("examples/robots/ur5.urdf")).unwrap();
    // The first revolute joint, j1_rz.
    let text = ur5.replacen("lower=\"-6.283185307179586\"", "lower=\"-1e308\"", 1);
    assert_ne!(text, ur5);
    let p = write(dir.path(), "robot.urdf", &text);
    let cell = repo("examples/scenarios/ur5-cell.toml");
    rejected(
        &[
            "reach".as_ref(),
            cell.as_os_str(),
            "--urdf".as_ref(),
            p.as_os_str(),
        ],
        &["robot.urdf", "joint 'j1_rz'", "-1e308", "1000 rad"],
    );
}

#[test]
fn deeply_nested_urdf_is_refused_before_parsing() {
    let dir = tempfile::tempdir().unwrap();
    let text = format!(
        "<robot name=\"r\">{}{}</robot>",
        "<link name=\"a\">".repeat(15_000),
        "</link>".repeat(15_000)
    );
    let p = write(dir.path(), "deep.urdf", &text);
    let cell = repo("examples/scenarios/ur5-cell.toml");
    rejected(
        &[
            "reach".as_ref(),
            cell.as_os_str(),
            "--urdf".as_ref(),
            p.as_os_str(),
        ],
        &["deep.urdf", "nested more than 64 deep"],
    );
}

#[test]
fn binary_stl_declaring_too_many_triangles_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let mut bytes = vec![0u8; 80];
    bytes.extend_from_slice(&u32::MAX.to_le_bytes());
    std::fs::write(dir.path().join("huge.stl"), &bytes).unwrap();
    let p = write(
        dir.path(),
        "s.toml",
        &format!(
            "{ROBOT}\n[[obstacle]]\nshape = \"mesh\"\nfile = \"huge.stl\"\nposition = [2.0, 0.0, 0.0]\n{TASK}"
        ),
    );
    rejected(
        &check(&p),
        &[
            "obstacle[0].file",
            "huge.stl",
            "4294967295 triangles",
            "limit of 5000000",
        ],
    );
}

#[test]
fn edges_refuses_counts_and_steps_it_cannot_run() {
    let s = repo("examples/scenarios/paper-2d.toml");
    let edges = |extra: &[&str]| -> Vec<std::ffi::OsString> {
        let mut v: Vec<std::ffi::OsString> = vec!["edges".into(), s.clone().into()];
        v.extend(extra.iter().map(|x| x.into()));
        v
    };
    // A count of 1e11 edges aborted on a 4.8 TB allocation; a non-finite or negative L_max
    // and no oracle sub-steps ran and printed meaningless rates.
    for (extra, parts) in [
        (
            &["--count", "100000000000"][..],
            &["--count", "100000000000", "from 1 to 100000"][..],
        ),
        (&["--count", "0"], &["--count", "0"]),
        (&["--substeps", "0"], &["--substeps", "0"]),
        (
            &["--lmax", "0.1,nan"],
            &["--lmax", "NaN", "positive and at most 1000000"],
        ),
        (&["--lmax", "-1"], &["--lmax", "-1"]),
        (
            &["--lmax", "1,2,3,4,5,6,7,8,9,10,11,12,13,14,15,16,17"],
            &["--lmax", "17 values", "at most 16"],
        ),
    ] {
        let args = edges(extra);
        let args: Vec<&OsStr> = args.iter().map(|a| a.as_os_str()).collect();
        rejected(&args, parts);
    }
}

/// `edges` prints any accepted `L_max` in its column: four decimals, or in exponent form where
/// those would not fit (`--lmax 1e300`, accepted until 2026-12-06, printed 301 digits; the
/// largest accepted now is 1e6).
#[test]
fn edges_prints_any_step_bound_in_its_column() {
    let s = repo("examples/scenarios/paper-2d.toml");
    let out = Command::new(BIN)
        .arg("edges")
        .arg(&s)
        .args([
            "--count",
            "10",
            "--substeps",
            "20",
            "--lmax",
            "1e6,0.5,0.00002",
        ])
        .stdin(Stdio::null())
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    let rows: Vec<&str> = text.lines().skip(2).collect();
    assert_eq!(rows.len(), 12, "{text}");
    let want = ["1.00e6", "0.5000", "2.00e-5"].map(|w| [w; 4]).concat();
    for (row, want) in rows.iter().zip(want) {
        assert_eq!(row.split_whitespace().next(), Some(want), "{text}");
        assert!(row.len() < 80, "{row}");
    }
}

/// An arm buried in an obstacle has no collision-free start: `edges` says so in one line after
/// a bounded search (an arm of 31,626 self pairs searched for minutes), instead of printing a
/// table of nothing.
#[test]
fn edges_without_a_collision_free_start_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let buried = "\n[[obstacle]]\nshape = \"sphere\"\nposition = [0.0, 0.0, 0.0]\nradius = 1.5\n";
    let p = write(
        dir.path(),
        "buried.toml",
        &format!("{ROBOT}{buried}\n[[task]]\npoint = [2.0, 0.0, 0.0]\n"),
    );
    let args = [
        "edges".as_ref(),
        p.as_os_str(),
        "--count".as_ref(),
        "3".as_ref(),
    ];
    rejected(
        &args,
        &["buried.toml", "no collision-free start", "13000 attempts"],
    );
}

#[test]
fn command_line_syntax_errors_are_one_line() {
    let s = repo("examples/scenarios/paper-2d.toml");
    for (args, part) in [
        (
            vec![
                OsStr::new("edges"),
                s.as_os_str(),
                "--count".as_ref(),
                "-5".as_ref(),
            ],
            "'-5'",
        ),
        (vec![OsStr::new("edges")], "<FILE>"),
        (
            vec![OsStr::new("reach"), s.as_os_str(), "--bogus".as_ref()],
            "--bogus",
        ),
        (vec![OsStr::new("frobnicate")], "frobnicate"),
    ] {
        let (code, stderr) = run(&args);
        assert_eq!(code, Some(2), "{args:?}: {stderr}");
        assert_eq!(stderr.lines().count(), 1, "{args:?}: {stderr}");
        assert!(
            stderr.starts_with("error: ") && stderr.contains(part),
            "{stderr}"
        );
    }
    // Help and version still print in full and succeed.
    let (code, _) = run(&[OsStr::new("edges"), "--help".as_ref()]);
    assert_eq!(code, Some(0));
}

/// A two-joint URDF robot whose three links carry `n` collision spheres each.
fn robot_with_spheres(n: usize) -> String {
    let spheres = |z: f64| {
        (0..n)
            .map(|i| {
                format!(
                    "<collision><origin xyz=\"{} 0 {z}\"/><geometry><sphere radius=\"0.01\"/></geometry></collision>",
                    i as f64 * 1e-5
                )
            })
            .collect::<String>()
    };
    format!(
        "<robot name=\"r\"><link name=\"a\">{}</link><link name=\"b\">{}</link><link name=\"c\">{}</link>\
         <joint name=\"j\" type=\"revolute\"><parent link=\"a\"/><child link=\"b\"/><axis xyz=\"0 0 1\"/>\
         <limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/></joint>\
         <joint name=\"j2\" type=\"revolute\"><parent link=\"b\"/><child link=\"c\"/><origin xyz=\"0.3 0 0\"/>\
         <axis xyz=\"0 1 0\"/><limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/></joint></robot>",
        spheres(0.0),
        spheres(0.1),
        spheres(0.2)
    )
}

#[test]
fn urdf_with_too_many_collision_elements_is_refused() {
    // 3 × 20,000 spheres (a 6 MB file) made 1.2 billion self pairs: the process was killed
    // for want of memory at 23 GB; 3 × 5,000 took 148 s and 4.3 GB.
    let dir = tempfile::tempdir().unwrap();
    let cell = repo("examples/scenarios/ur5-cell.toml");
    let p = write(dir.path(), "many.urdf", &robot_with_spheres(334));
    rejected(
        &[
            "reach".as_ref(),
            cell.as_os_str(),
            "--urdf".as_ref(),
            p.as_os_str(),
        ],
        &["many.urdf", "<collision>", "1002 elements", "at most 1000"],
    );
    // At the limit the robot is read.
    let p = write(dir.path(), "fine.urdf", &robot_with_spheres(333));
    view_reads(&cell, &p, dir.path());
}

#[test]
fn urdf_output_never_overwritten_by_its_own_srdf() {
    let dir = tempfile::tempdir().unwrap();
    let d = write(dir.path(), "d.json", &design("0.3", "[-1, 1]", 2));
    let urdf = |out: &Path| -> Vec<std::ffi::OsString> {
        vec![
            "urdf".into(),
            d.clone().into_os_string(),
            "-o".into(),
            out.as_os_str().to_owned(),
        ]
    };
    // `-o x.srdf` would write the URDF, then the SRDF over it.
    let same = dir.path().join("x.srdf");
    let a = urdf(&same);
    let a: Vec<&OsStr> = a.iter().map(|s| s.as_os_str()).collect();
    rejected(&a, &["-o", "x.srdf", "must not end in .srdf"]);
    assert!(!same.exists(), "nothing may be written");
    // An SRDF path that is a directory is refused before the URDF is written.
    std::fs::create_dir(dir.path().join("r.srdf")).unwrap();
    let out = dir.path().join("r.urdf");
    let a = urdf(&out);
    let a: Vec<&OsStr> = a.iter().map(|s| s.as_os_str()).collect();
    rejected(&a, &["r.srdf", "is a directory"]);
    assert!(!out.exists(), "no URDF may be left without its SRDF");
    // The usual case writes both.
    let ok = dir.path().join("ok.urdf");
    let a = urdf(&ok);
    let a: Vec<&OsStr> = a.iter().map(|s| s.as_os_str()).collect();
    let (code, stderr) = run(&a);
    assert_eq!(code, Some(0), "{stderr}");
    assert!(ok.is_file() && dir.path().join("ok.srdf").is_file());
}

/// An output given as `/dev/stdout` while stdout is a pipe (as in `| jq`) is written into the
/// pipe, alone: the command's messages go to stderr. `urdf -o /dev/null` or `-o /dev/stdout`
/// writes no SRDF beside it (`/dev/null.srdf`) unless --srdf names one. And a reader that
/// closes the pipe early (`| head -1`) does not stop the command before it writes its files.
#[cfg(unix)]
#[test]
fn outputs_into_stdout_pipes_come_through_alone() {
    let dir = tempfile::tempdir().unwrap();
    let piped = |args: &[&OsStr]| {
        let out = Command::new(BIN)
            .args(args)
            .stdin(Stdio::null())
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
        assert!(out.status.success(), "{args:?}: {stderr}");
        (String::from_utf8_lossy(&out.stdout).into_owned(), stderr)
    };
    let cell = repo("examples/scenarios/paper-2d.toml");
    let (json, said) = piped(&[
        "reach".as_ref(),
        cell.as_os_str(),
        "--json".as_ref(),
        "/dev/stdout".as_ref(),
    ]);
    let v: serde_json::Value = serde_json::from_str(&json).expect("stdout is the JSON alone");
    assert_eq!(v["reachability"], 1.0);
    assert!(said.contains("R = 1.000"), "{said}");

    let d = write(dir.path(), "d.json", &design("0.3", "[-1, 1]", 2));
    let (urdf, said) = piped(&[
        "urdf".as_ref(),
        d.as_os_str(),
        "-o".as_ref(),
        "/dev/stdout".as_ref(),
    ]);
    assert!(
        urdf.starts_with("<?xml") && urdf.trim_end().ends_with("</robot>"),
        "{urdf}"
    );
    assert!(said.contains("no SRDF"), "{said}");
    let srdf = dir.path().join("d.srdf");
    let (_, said) = piped(&[
        "urdf".as_ref(),
        d.as_os_str(),
        "-o".as_ref(),
        "/dev/null".as_ref(),
        "--srdf".as_ref(),
        srdf.as_os_str(),
    ]);
    assert!(srdf.is_file(), "{said}");
    assert!(!Path::new("/dev/null.srdf").exists());
    // The same file as -o, however spelt, is refused as --srdf.
    let o = dir.path().join("o.urdf");
    let dotted = dir.path().join(".").join("o.urdf");
    rejected(
        &[
            "urdf".as_ref(),
            d.as_os_str(),
            "-o".as_ref(),
            o.as_os_str(),
            "--srdf".as_ref(),
            dotted.as_os_str(),
        ],
        &["is also --srdf"],
    );
    assert!(!o.exists());
    // stdout redirected to a file: the URDF alone goes there, and no SRDF beside /dev/stdout.
    let file = dir.path().join("redirected.urdf");
    let out = Command::new(BIN)
        .args([
            OsStr::new("urdf"),
            d.as_os_str(),
            "-o".as_ref(),
            "/dev/stdout".as_ref(),
        ])
        .stdout(std::fs::File::create(&file).unwrap())
        .output()
        .unwrap();
    let said = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success() && said.contains("no SRDF"), "{said}");
    let urdf = std::fs::read_to_string(&file).unwrap();
    assert!(
        urdf.starts_with("<?xml") && urdf.trim_end().ends_with("</robot>"),
        "{urdf}"
    );
    // A regular file under /dev (a tmpfs such as /dev/shm) gets its SRDF beside it.
    if Path::new("/dev/shm").is_dir() {
        let shm = PathBuf::from(format!(
            "/dev/shm/kinsynth-test-{}.urdf",
            std::process::id()
        ));
        let srdf = shm.with_extension("srdf");
        let out = Command::new(BIN)
            .args([
                OsStr::new("urdf"),
                d.as_os_str(),
                "-o".as_ref(),
                shm.as_os_str(),
            ])
            .output()
            .unwrap();
        let written = srdf.is_file();
        let _ = (std::fs::remove_file(&shm), std::fs::remove_file(&srdf));
        assert!(
            out.status.success() && written,
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    // stdout and the output both /dev/null: the messages stay on stdout (not on stderr).
    let out = Command::new(BIN)
        .args([
            OsStr::new("reach"),
            cell.as_os_str(),
            "--json".as_ref(),
            "/dev/null".as_ref(),
        ])
        .stdout(Stdio::null())
        .output()
        .unwrap();
    assert!(out.status.success());
    assert_eq!(String::from_utf8_lossy(&out.stderr), "");

    // `reach … --json FILE | head -c 1`: the reader is gone after the first line, the JSON
    // is written all the same.
    for attempt in 0..3 {
        let report = dir.path().join(format!("r{attempt}.json"));
        let mut child = Command::new(BIN)
            .args(
                [cell.as_os_str(), report.as_os_str()]
                    .iter()
                    .enumerate()
                    .flat_map(|(i, a)| {
                        if i == 0 {
                            vec![OsStr::new("reach"), a]
                        } else {
                            vec![OsStr::new("--json"), a]
                        }
                    }),
            )
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        drop(child.stdout.take()); // the reader closes at once
        let status = child.wait().unwrap();
        assert!(status.success());
        assert!(report.is_file(), "attempt {attempt}: no report written");
    }
}

/// A file of the wrong kind is named as such: a TOML or a URDF given as a design, a best.json
/// given as a reach report, an SRDF as the URDF and a URDF as the SRDF; a key given twice in a
/// design is refused (the last one used to win), and a joint that is its own parent is named.
#[test]
fn files_of_the_wrong_kind_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let o = |name: &str| d.join(name).into_os_string();
    let cell = repo("examples/scenarios/ur5-cell.toml");
    let ur5 = repo("examples/robots/ur5.urdf");
    let out = o("x.urdf");
    let args = |v: &[&OsStr]| v.iter().map(|a| a.to_os_string()).collect::<Vec<_>>();
    let refused = |v: Vec<std::ffi::OsString>, parts: &[&str]| {
        let v: Vec<&OsStr> = v.iter().map(|a| a.as_os_str()).collect();
        rejected(&v, parts)
    };
    refused(
        args(&["urdf".as_ref(), cell.as_os_str(), "-o".as_ref(), &out]),
        &["ur5-cell.toml", "not a JSON object; a design is one"],
    );
    refused(
        args(&["urdf".as_ref(), ur5.as_os_str(), "-o".as_ref(), &out]),
        &["ur5.urdf", "an XML file such as a URDF"],
    );
    let twice = write(
        d,
        "twice.json",
        r#"{"link_radius": 0.02, "link_radius": 0.5, "colliders_per_link": 4, "links": [{"a": 0.3, "axes": {"ry": [-1, 1]}}]}"#,
    );
    refused(
        args(&["urdf".as_ref(), twice.as_os_str(), "-o".as_ref(), &out]),
        &["twice.json", "duplicate field `link_radius`"],
    );
    let best = write(
        d,
        "best.json",
        &format!(
            r#"{{"cost": 1, "design": {}}}"#,
            design("0.3", "[-1, 1]", 2)
        ),
    );
    refused(
        args(&[
            "view".as_ref(),
            repo("examples/scenarios/paper-2d.toml").as_os_str(),
            "--reach".as_ref(),
            best.as_os_str(),
            "-o".as_ref(),
            &o("v.html"),
        ]),
        &["best.json", "missing field", "an optimiser's best.json"],
    );
    let srdf = write(
        d,
        "r.srdf",
        "<robot name=\"r\">\n<disable_collisions link1=\"a\" link2=\"b\" reason=\"Never\"/>\n</robot>\n",
    );
    refused(
        args(&[
            "reach".as_ref(),
            cell.as_os_str(),
            "--urdf".as_ref(),
            srdf.as_os_str(),
        ]),
        &["r.srdf", "no <link> elements: not a URDF robot"],
    );
    refused(
        args(&[
            "reach".as_ref(),
            cell.as_os_str(),
            "--urdf".as_ref(),
            ur5.as_os_str(),
            "--srdf".as_ref(),
            ur5.as_os_str(),
        ]),
        &["ur5.urdf", "<link> elements: a URDF robot, not an SRDF"],
    );
    let looped = write(
        d,
        "loop.urdf",
        "<robot name=\"l\"><link name=\"a\"/><joint name=\"j1\" type=\"revolute\"><parent link=\"a\"/><child link=\"a\"/><limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/></joint></robot>\n",
    );
    refused(
        args(&[
            "reach".as_ref(),
            cell.as_os_str(),
            "--urdf".as_ref(),
            looped.as_os_str(),
        ]),
        &["loop.urdf", "joint 'j1'", "cycle through link 'a'"],
    );
}

/// The scenario's mesh-triangle limit counts distinct meshes: a file placed again with the same
/// representation and scale shares its shape and adds nothing, one at another scale is another
/// mesh. An OBJ tetrahedron whose four faces repeat 650,000 times (2.6M triangles) is placed
/// three times (7.8M triangles, one mesh: accepted), then at a second scale (5.2M: refused).
#[test]
fn scene_mesh_limit_counts_distinct_meshes() {
    use kinsynth::limits::MAX_SCENE_MESH_TRIANGLES;
    let dir = tempfile::tempdir().unwrap();
    let repeats = MAX_SCENE_MESH_TRIANGLES / 8 + 25_000;
    let mut obj = String::from("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n");
    let faces = "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
    obj.reserve(faces.len() * repeats);
    for _ in 0..repeats {
        obj.push_str(faces);
    }
    write(dir.path(), "tetra.obj", &obj);
    let placed = |scale: f64, x: f64| {
        format!(
            "\n[[obstacle]]\nshape = \"mesh\"\nfile = \"tetra.obj\"\nscale = {scale}\nposition = [{x}, 5.0, 5.0]\n"
        )
    };
    let copies = format!(
        "{ROBOT}{TASK}{}{}{}",
        placed(0.1, 3.0),
        placed(0.1, 4.0),
        placed(0.1, 5.0)
    );
    let p = write(dir.path(), "copies.toml", &copies);
    let (code, stderr) = run(&check(&p));
    assert_eq!(code, Some(0), "{stderr}");
    let two = format!("{copies}{}", placed(0.2, 6.0));
    let p = write(dir.path(), "two.toml", &two);
    rejected(
        &check(&p),
        &[
            "two.toml",
            "obstacle[3].file",
            "tetra.obj",
            "5200000 triangles",
            "5000000",
        ],
    );
    // All meshes are counted before the first is built: a first mesh that cannot be built
    // (its faces name a vertex it lacks) is not reached when the two are over the limit.
    let mut broken = String::from("v 0 0 0\nv 1 0 0\n");
    broken.push_str(&"f 1 2 3\nf 2 1 3\nf 1 3 2\nf 3 2 1\n".repeat(repeats));
    write(dir.path(), "broken.obj", &broken);
    let first = placed(0.1, 3.0).replace("tetra.obj", "broken.obj");
    let p = write(
        dir.path(),
        "first.toml",
        &format!("{ROBOT}{TASK}{first}{}", placed(0.1, 4.0)),
    );
    rejected(
        &check(&p),
        &["obstacle[1].file", "tetra.obj", "5200000 triangles"],
    );
    // Alone, the first is refused for what it is.
    let p = write(dir.path(), "alone.toml", &format!("{ROBOT}{TASK}{first}"));
    rejected(&check(&p), &["obstacle[0]", "broken.obj"]);
}

/// Iterations cost more on designs of many axes (the nearest-node search scans the tree):
/// iterations × the largest design's axes are at most 2,400,000, for `max_iterations` and the
/// schedule's budgets; 64 links of six axes allow 6,250. Inverse kinematics makes them cost more
/// with its steps: iterations × axes × `ik_steps` are at most 48,000,000, so 10,000 steps
/// allow 12 iterations there (10,000 steps on 8 axes for 100,000 iterations ran for minutes).
/// The allowed-collision samples are at most 100,000.
#[test]
fn iteration_limit_shrinks_with_the_axes() {
    let dir = tempfile::tempdir().unwrap();
    let robot = "[robot]\nlinks = 64\n[robot.uniform]\na = [0.0, 0.05]\naxes.rx = { min = -1, max = 1 }\naxes.ry = { min = -1, max = 1 }\naxes.rz = { min = -1, max = 1 }\naxes.tx = { min = -0.01, max = 0.01 }\naxes.ty = { min = -0.01, max = 0.01 }\naxes.tz = { min = -0.01, max = 0.01 }\n";
    for (planner, ok, parts) in [
        ("max_iterations = 6250", true, vec![]),
        (
            "max_iterations = 6251",
            false,
            vec![
                "planner.max_iterations = 6251",
                "384 free axes",
                "at most 6250",
            ],
        ),
        (
            "schedule = { l_max = [0.5, 0.2], iterations = [2000, 100000] }",
            false,
            vec!["planner.schedule.iterations = 100000", "at most 6250"],
        ),
        ("max_iterations = 12\nik_steps = 10000", true, vec![]),
        (
            "max_iterations = 13\nik_steps = 10000",
            false,
            vec![
                "planner.max_iterations = 13",
                "planner.ik_steps is 10000",
                "at most 12 iterations",
            ],
        ),
    ] {
        let p = write(
            dir.path(),
            "s.toml",
            &format!("{robot}[planner]\n{planner}\n{TASK}"),
        );
        if ok {
            let (code, stderr) = run(&check(&p));
            assert_eq!(code, Some(0), "{stderr}");
        } else {
            let mut all = vec!["s.toml"];
            all.extend(parts);
            rejected(&check(&p), &all);
        }
    }
    at_the_limit(
        dir.path(),
        100_000,
        |n| format!("{ROBOT}self_collision_samples = {n}\n{TASK}"),
        &["robot.self_collision_samples", "100001", "at most 100000"],
    );
}

/// A long value quoted in an error keeps its ends only: a 1,000,000-character string where a
/// number belongs gave a 1 MB error line.
#[test]
fn long_values_in_errors_are_shortened() {
    let dir = tempfile::tempdir().unwrap();
    let text = format!("[robot]\nlinks = \"{}\"\n{TASK}", "a".repeat(1_000_000));
    let p = write(dir.path(), "long.toml", &text);
    let stderr = rejected(&check(&p), &["long.toml", "links", "characters]"]);
    assert!(stderr.len() < 600, "{} bytes: {stderr}", stderr.len());
}

/// A URDF the parser refuses for a bad number or shape is placed: element, attribute, value and
/// line (the parser said only "invalid float literal").
#[test]
fn urdf_parse_faults_name_element_attribute_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let ur5 = std::fs::read_to_string(repo("examples/robots/ur5.urdf")).unwrap();
    let cell = repo("examples/scenarios/ur5-cell.toml");
    // The line of `needle` in `text` (found mid-line: the lines before it and its own).
    let at = |text: &str, needle: &str| text[..text.find(needle).unwrap()].lines().count();
    let radius = ur5.find("radius=\"").unwrap();
    let axis = ur5.replacen("<axis xyz=\"0 0 1\"", "<axis xyz=\"0 1\"", 1);
    let sphere = "<sphere radius=\"0.05\"/>";
    let geometry = ur5.find("<geometry>").unwrap() + "<geometry>".len();
    for (name, text, parts) in [
        (
            "radius.urdf",
            format!("{}radius=\"abc{}", &ur5[..radius], &ur5[radius + 8..]),
            vec![
                format!("line {}", at(&ur5, "radius=\"")),
                "is not a number".into(),
            ],
        ),
        (
            "axis.urdf",
            axis.clone(),
            vec![
                format!(
                    "line {}: <axis xyz=\"0 1\">",
                    at(&axis, "<axis xyz=\"0 1\"")
                ),
                "2 numbers, expected 3".into(),
            ],
        ),
        (
            "syntax.urdf",
            ur5.replacen(" iyz=\"0\" izz=", " iyz=\"0\"(izz=", 1),
            vec![format!(
                "expected a whitespace not '(' at {}:",
                at(&ur5, " iyz=\"0\" izz=")
            )],
        ),
        (
            "shapes.urdf",
            format!("{}{sphere}{}", &ur5[..geometry], &ur5[geometry..]),
            vec!["holds 2 shapes".into(), "it must hold exactly one".into()],
        ),
        (
            "unnamed.urdf",
            ur5.replacen("<joint name=\"j1_rz\"", "<joint", 1),
            vec![
                format!("line {}: <joint>", at(&ur5, "<joint name=\"j1_rz\"")),
                "has no name=\"…\" attribute; it is required".into(),
            ],
        ),
        (
            "parentless.urdf",
            ur5.replacen("<parent link=", "<parent lnk=", 1),
            vec![
                format!("line {}: <parent>", at(&ur5, "<parent link=")),
                "has no link=\"…\" attribute".into(),
            ],
        ),
        (
            "spinny.urdf",
            ur5.replacen("type=\"revolute\"", "type=\"spinny\"", 1),
            vec![
                format!("line {}: <joint name=", at(&ur5, "type=\"revolute\"")),
                "unknown variant `spinny`".into(),
            ],
        ),
        (
            "cone.urdf",
            ur5.replacen("<cylinder", "<cone", 1),
            vec![
                format!("line {}: <geometry>", at(&ur5, "<cylinder") - 1),
                "unknown variant `cone`".into(),
            ],
        ),
        (
            "inertia.urdf",
            ur5.replacen("ixx=\"0.000000001\"", "ixx=\"nan\"", 1),
            vec![
                format!("line {}: link 'base_link', <inertial>", at(&ur5, "ixx=")),
                "<inertia ixx=\"nan\">: every value must be a finite number".into(),
            ],
        ),
        (
            "limit.urdf",
            ur5.replacen("upper=\"", "upper=\"1e400", 1),
            vec![
                format!("line {}: joint '", at(&ur5, "upper=\"")),
                "every value must be a finite number".into(),
            ],
        ),
        (
            "twice.urdf",
            format!(
                "{}<origin/>{}",
                &ur5[..geometry - 10],
                &ur5[geometry - 10..]
            ),
            vec!["holds 2 <origin> elements; at most one is allowed".into()],
        ),
    ] {
        let p = write(dir.path(), name, &text);
        let mut all: Vec<&str> = vec![name, "not a valid URDF"];
        all.extend(parts.iter().map(String::as_str));
        rejected(
            &[
                "reach".as_ref(),
                cell.as_os_str(),
                "--urdf".as_ref(),
                p.as_os_str(),
            ],
            &all,
        );
    }
}

/// A `best.json` whose planner settings hold a value of the wrong type names its field.
#[test]
fn best_json_planner_faults_name_the_field() {
    let dir = tempfile::tempdir().unwrap();
    let best = format!(
        r#"{{"design": {}, "seed": 1, "stream": 0, "planner": {{"max_iterations": 0.5}}}}"#,
        design("0.3", "[-1, 1]", 2)
    );
    let p = write(dir.path(), "best.json", &best);
    let cell = repo("examples/scenarios/paper-2d.toml");
    rejected(
        &[
            "reach".as_ref(),
            cell.as_os_str(),
            "--design".as_ref(),
            p.as_os_str(),
        ],
        &["best.json: planner.max_iterations: invalid type: floating point `0.5`"],
    );
}

/// `reach` checks its output locations before planning: a `--trajectories` path that is a file
/// fails it before the `--json` report is written, and a `--json` path in a missing folder too.
#[test]
fn reach_checks_its_outputs_before_writing_any() {
    let dir = tempfile::tempdir().unwrap();
    let cell = repo("examples/scenarios/paper-2d.toml");
    let report = dir.path().join("r.json");
    let file = write(dir.path(), "t", "a file");
    rejected(
        &[
            "reach".as_ref(),
            cell.as_os_str(),
            "--json".as_ref(),
            report.as_os_str(),
            "--trajectories".as_ref(),
            file.as_os_str(),
        ],
        &["t: cannot write: exists and is not a folder"],
    );
    assert!(!report.exists(), "no report may be written");
    let nowhere = dir.path().join("no/such/folder/r.json");
    rejected(
        &[
            "reach".as_ref(),
            cell.as_os_str(),
            "--json".as_ref(),
            nowhere.as_os_str(),
        ],
        &["r.json: cannot write: its folder does not exist"],
    );
    let slash = format!("{}/u/", dir.path().display());
    rejected(
        &[
            "reach".as_ref(),
            cell.as_os_str(),
            "--json".as_ref(),
            slash.as_ref(),
        ],
        &["u/: cannot write: names a folder (it ends with /), not a file"],
    );
    let same = dir.path().join("same");
    rejected(
        &[
            "reach".as_ref(),
            cell.as_os_str(),
            "--json".as_ref(),
            same.as_os_str(),
            "--trajectories".as_ref(),
            same.as_os_str(),
        ],
        &["--trajectories", "is also the --json report"],
    );
    assert!(!same.exists(), "nothing may be written");
}

#[test]
fn a_file_name_with_a_newline_gives_a_one_line_error() {
    let dir = tempfile::tempdir().unwrap();
    let name = dir.path().join("cell\nnext.toml");
    rejected(
        &["check".as_ref(), name.as_os_str()],
        &["cell\\nnext.toml: cannot read"],
    );
    // In a value read from a file too: a mesh named with a newline.
    let cell = write(
        dir.path(),
        "c.toml",
        &format!("{ROBOT}{TASK}\n[[obstacle]]\nshape = \"mesh\"\nfile = \"a\\nb.stl\"\nposition = [1.0, 1.0, 1.0]\n"),
    );
    rejected(&check(&cell), &["a\\nb.stl"]);
}

#[test]
fn a_trajectory_name_taken_by_a_folder_fails_before_any_file_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let cell = repo("examples/scenarios/paper-2d.toml");
    let report = dir.path().join("r.json");
    let traj = dir.path().join("traj");
    std::fs::create_dir_all(traj.join("task_3.csv")).unwrap();
    rejected(
        &[
            "reach".as_ref(),
            cell.as_os_str(),
            "--json".as_ref(),
            report.as_os_str(),
            "--trajectories".as_ref(),
            traj.as_os_str(),
        ],
        &["task_3.csv: cannot write: is a directory"],
    );
    assert!(!report.exists(), "no report may be written");
    let left: Vec<_> = std::fs::read_dir(&traj).unwrap().collect();
    assert_eq!(left.len(), 1, "only the folder in the way stays: {left:?}");
}

/// A table header of 128 dotted keys passes the reader's recursion limit; the error says what
/// that limit is about (the reader said only "recursion limit").
#[test]
fn deep_dotted_header_names_the_limit() {
    let dir = tempfile::tempdir().unwrap();
    let header = vec!["a"; 128].join(".");
    let p = write(
        dir.path(),
        "deep.toml",
        &format!("{ROBOT}{TASK}\n[{header}]\nx = 1\n"),
    );
    rejected(
        &check(&p),
        &[
            "deep.toml",
            "recursion limit",
            "nested deeper than the TOML reader allows",
        ],
    );
}

/// A key given twice is named (the reader said only "duplicate key", with its line).
#[test]
fn duplicate_key_is_named() {
    let dir = tempfile::tempdir().unwrap();
    for (text, parts) in [
        (
            "seed = 1\nseed = 2\n",
            ["line 2, column 1", "duplicate key `seed`"],
        ),
        (
            "[robot]\nlinks = 2\n[robot]\nlinks = 3\n",
            ["line 3", "duplicate key `robot`"],
        ),
    ] {
        let p = write(dir.path(), "dup.toml", &format!("{text}{TASK}"));
        rejected(&check(&p), &["dup.toml", parts[0], parts[1]]);
    }
}

/// The optimisers' settings in a scenario are checked by the rules a checkpoint's are held to
/// on resume, named under the scenario's sections.
#[test]
fn optimizer_settings_are_named_under_their_section() {
    let dir = tempfile::tempdir().unwrap();
    for (section, parts) in [
        (
            "[optimizer]\npopulation = 4\n[optimizer.ga]\nelites = 4\n",
            [
                "optimizer.ga.elites = 4",
                "must be less than the population (4)",
            ],
        ),
        (
            "[optimizer.ga]\nzero_rate = 1.5\n",
            [
                "optimizer.ga.zero_rate = 1.5",
                "must be a probability in [0, 1]",
            ],
        ),
        (
            "[optimizer.pso]\nmax_velocity = -1.0\n",
            [
                "optimizer.pso.max_velocity = -1",
                "must be finite, not negative",
            ],
        ),
        (
            "[optimizer.asa]\ntemperature_ratio = 0.0\n",
            ["optimizer.asa.temperature_ratio = 0", "must lie in (0, 1]"],
        ),
        (
            "[optimizer.asa]\nbatch = 10001\n",
            ["optimizer.asa.batch = 10001", "at most 10000"],
        ),
        (
            "[optimizer]\npopulation = 4\nmigration = { interval = 10, count = 5 }\n",
            ["optimizer.migration.count = 5", "must be at most 4"],
        ),
        // A size in an algorithm's own section would be overridden by optimizer.population.
        (
            "[optimizer.ga]\npopulation = 8\n",
            [
                "optimizer.ga.population = 8",
                "is optimizer.population (32): set it there",
            ],
        ),
        (
            "[optimizer]\npopulation = 16\n[optimizer.pso]\nswarm = 32\n",
            [
                "optimizer.pso.swarm = 32",
                "is optimizer.population (16): set it there",
            ],
        ),
    ] {
        let p = write(dir.path(), "o.toml", &format!("{ROBOT}{TASK}{section}"));
        rejected(&check(&p), &["o.toml", parts[0], parts[1]]);
    }
    // The size given in both places alike (as scenarios generated by earlier versions have
    // it) is accepted.
    let same = "[optimizer]\npopulation = 16\n[optimizer.ga]\npopulation = 16\n[optimizer.pso]\nswarm = 16\n";
    let p = write(dir.path(), "same.toml", &format!("{ROBOT}{TASK}{same}"));
    let (code, stderr) = run(&check(&p));
    assert_eq!(code, Some(0), "{stderr}");
}

/// No output may replace an input: `view -o`, `reach --json`, `--write-srdf` and
/// `--trajectories`, `urdf -o` (and the SRDF beside it) and `optimize --out` naming an input,
/// directly, through another relative path or through a symbolic link, are refused before
/// anything is written, naming the flag, the path and the input.
#[test]
fn an_output_that_is_an_input_is_refused_before_anything_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let text = std::fs::read_to_string(repo("examples/scenarios/paper-2d.toml")).unwrap();
    let s = write(d, "s.toml", &text);
    let design_text = design("0.3", "[-1, 1]", 2);
    let dj = write(d, "d.json", &design_text);
    std::fs::create_dir(d.join("sub")).unwrap();
    let around = d.join("sub/../s.toml");
    #[cfg(unix)]
    std::os::unix::fs::symlink(&s, d.join("link.toml")).unwrap();
    #[cfg(not(unix))]
    std::fs::copy(&s, d.join("link.toml")).unwrap();
    let link = d.join("link.toml");
    let os = |v: &[&Path]| -> Vec<std::ffi::OsString> {
        v.iter().map(|p| p.as_os_str().to_owned()).collect()
    };
    let cases: Vec<(Vec<std::ffi::OsString>, Vec<&str>)> = vec![
        (
            os(&[Path::new("view"), &s, Path::new("-o"), &s]),
            vec!["-o = ", "s.toml: is also the input scenario"],
        ),
        (
            os(&[Path::new("view"), &s, Path::new("-o"), &around]),
            vec!["-o = ", "is also the input scenario"],
        ),
        (
            os(&[Path::new("reach"), &s, Path::new("--json"), &link]),
            vec!["--json = ", "link.toml: is also the input scenario"],
        ),
        (
            os(&[Path::new("reach"), &s, Path::new("--write-srdf"), &s]),
            vec!["--write-srdf = ", "is also the input scenario"],
        ),
        (
            os(&[
                Path::new("reach"),
                &s,
                Path::new("--design"),
                &dj,
                Path::new("--json"),
                &dj,
            ]),
            vec!["--json = ", "is also the --design file"],
        ),
        (
            os(&[Path::new("urdf"), &dj, Path::new("-o"), &dj]),
            vec!["-o = ", "d.json: is also the input design"],
        ),
        (
            os(&[
                Path::new("optimize"),
                &s,
                Path::new("--out"),
                d,
                Path::new("--evaluations"),
                Path::new("2"),
            ]),
            vec!["--out = ", "its file best.json is also the input scenario"],
        ),
    ];
    // The scenario under the names the outputs take.
    let best = write(d, "best.json", &text);
    let task = write(d, "task_0.json", &text);
    let srdf_scenario = write(d, "x.srdf", &text);
    let mut cases = cases;
    cases[6].0[1] = best.as_os_str().to_owned();
    cases.push((
        os(&[Path::new("reach"), &task, Path::new("--trajectories"), d]),
        vec![
            "--trajectories = ",
            "its file task_0.json is also the input scenario",
        ],
    ));
    cases.push((
        os(&[
            Path::new("urdf"),
            &dj,
            Path::new("-o"),
            &d.join("x.urdf"),
            Path::new("--scenario"),
            &srdf_scenario,
        ]),
        vec![
            "-o = ",
            "x.urdf: the SRDF beside it, ",
            "x.srdf, is also the input scenario",
        ],
    ));
    let before: Vec<_> = std::fs::read_dir(d)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    for (args, parts) in &cases {
        let a: Vec<&OsStr> = args.iter().map(|s| s.as_os_str()).collect();
        rejected(&a, parts);
    }
    let after: Vec<_> = std::fs::read_dir(d)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    assert_eq!(
        before.len(),
        after.len(),
        "nothing may be written: {after:?}"
    );
    for f in [&s, &best, &task, &srdf_scenario] {
        assert_eq!(std::fs::read_to_string(f).unwrap(), text, "{}", f.display());
    }
    assert_eq!(std::fs::read_to_string(&dj).unwrap(), design_text);
    // A new output beside the inputs is written as before.
    let page = d.join("page.html");
    let (code, stderr) = run(&[
        "view".as_ref(),
        s.as_os_str(),
        "-o".as_ref(),
        page.as_os_str(),
    ]);
    assert_eq!(code, Some(0), "{stderr}");
    assert!(page.is_file());
}

/// A table given as an array is refused wherever a table is expected, at any depth, in a
/// scenario, a design and a `best.json`: serde would otherwise take the elements for the
/// fields in order and ignore the rest. Arrays where arrays belong keep working.
#[test]
fn tables_given_as_arrays_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    for (text, field) in [
        (
            ROBOT.replace(
                "ry = { min = -3.0, max = 3.0 }",
                "ry = [-1.0, 1.0, 99.0, \"ignored\", true]",
            ),
            "robot.uniform.axes.ry",
        ),
        (
            format!("{ROBOT}[[robot.link]]\nindex = 1\naxes = {{ rz = [1.0, 2.0] }}\n"),
            "robot.link[0].axes.rz",
        ),
        (
            ROBOT.replace("uniform = {", "base = [[0, 0, 0]]\nuniform = {"),
            "robot.base",
        ),
        (format!("objective = [1.0, 2.0, 3.0]\n{ROBOT}"), "objective"),
        (format!("planner = []\n{ROBOT}"), "planner"),
        (
            format!("{ROBOT}[planner]\nschedule = [[1.2, 0.4], [200, 500]]\n"),
            "planner.schedule",
        ),
        (
            format!("{ROBOT}[optimizer]\nga = [1, 2, 3]\n"),
            "optimizer.ga",
        ),
        (
            format!("{ROBOT}[optimizer]\nmigration = [10, 2]\n"),
            "optimizer.migration",
        ),
        (
            format!("{ROBOT}[[task]]\npoint = [0.4, 0.0, 0.3]\norientation = [[0, 0, 0]]\n"),
            "task[0].orientation",
        ),
        (format!("task = [[[0.5, 0.0, 0.3]]]\n{ROBOT}"), "task[0]"),
    ] {
        let text = match text.contains("[[task]]") || text.contains("task = ") {
            true => text,
            false => format!("{text}{TASK}"),
        };
        let p = write(dir.path(), "t.toml", &text);
        let e = rejected(&check(&p), &["t.toml", &format!(": {field}: ")]);
        assert!(e.contains("invalid type: sequence, expected struct"), "{e}");
    }
    let cell = repo("examples/scenarios/paper-2d.toml");
    let good = design("0.3", "[-1, 1]", 2);
    let bad_link = good.replacen(r#"{"a": 0.3, "axes": {"ry": [-1, 1]}}"#, "[]", 1);
    let bad_base = good.replacen('{', r#"{"base": [[0, 0, 0], [0, 0, 0]], "#, 1);
    let bad_axes = good.replacen(r#"{"ry": [-1, 1]}"#, "[[-1, 1]]", 1);
    let best = format!(r#"{{"design": {good}, "seed": 1, "stream": 0, "planner": [0.5, 0.1]}}"#);
    for (name, text, field) in [
        ("d.json", bad_link, "links[0]"),
        ("d.json", bad_base, "base"),
        ("d.json", bad_axes, "links[0].axes"),
        ("best.json", best, "planner"),
    ] {
        let p = write(dir.path(), name, &text);
        let e = rejected(
            &[
                "reach".as_ref(),
                cell.as_os_str(),
                "--design".as_ref(),
                p.as_os_str(),
            ],
            &[&format!("{name}: {field}: ")],
        );
        assert!(e.contains("invalid type: sequence, expected struct"), "{e}");
    }
    // Arrays where the format has arrays still read.
    let p = write(dir.path(), "d.json", &good);
    let (code, stderr) = run(&[
        "reach".as_ref(),
        cell.as_os_str(),
        "--design".as_ref(),
        p.as_os_str(),
    ]);
    assert_eq!(code, Some(0), "{stderr}");
}

/// A URDF arm of three revolute joints `j1`–`j3` over links `base_link`, `l1`–`l3`, with
/// `extra` added before `</robot>` and `base_geometry` as the base link's collision geometry.
fn three_joint_urdf(base_geometry: &str, extra: &str) -> String {
    let link = |name: &str, geometry: &str| {
        format!(
            "<link name=\"{name}\"><collision><origin xyz=\"0 0 0.05\"/><geometry>{geometry}</geometry></collision></link>\n"
        )
    };
    let cylinder = "<cylinder radius=\"0.03\" length=\"0.1\"/>";
    let joint = |name: &str, parent: &str, child: &str| {
        format!(
            "<joint name=\"{name}\" type=\"revolute\"><parent link=\"{parent}\"/><child link=\"{child}\"/>\
             <origin xyz=\"0.3 0 0\"/><axis xyz=\"0 1 0\"/><limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/></joint>\n"
        )
    };
    format!(
        "<?xml version=\"1.0\"?>\n<robot name=\"r\">\n{}{}{}{}{}{}{}{extra}</robot>\n",
        link("base_link", base_geometry),
        link("l1", cylinder),
        link("l2", cylinder),
        link("l3", cylinder),
        joint("j1", "base_link", "l1"),
        joint("j2", "l1", "l2"),
        joint("j3", "l2", "l3"),
    )
}

fn reach_urdf<'a>(cell: &'a Path, urdf: &'a Path) -> Vec<&'a OsStr> {
    vec![
        "reach".as_ref(),
        cell.as_os_str(),
        "--urdf".as_ref(),
        urdf.as_os_str(),
    ]
}

/// Two joints or two links of one name are refused: the chain, paths, trajectories and SRDF
/// pairs are keyed by these names.
#[test]
fn urdf_names_given_twice_are_refused() {
    let cell = repo("examples/scenarios/ur5-cell.toml");
    let dir = tempfile::tempdir().unwrap();
    let cylinder = "<cylinder radius=\"0.03\" length=\"0.1\"/>";
    let good = three_joint_urdf(cylinder, "");
    let twin_joint = good.replacen("joint name=\"j2\"", "joint name=\"j1\"", 1);
    let twin_link = three_joint_urdf(
        cylinder,
        "<link name=\"l2\"><collision><geometry><sphere radius=\"0.1\"/></geometry></collision></link>\n",
    );
    for (name, text, parts) in [
        (
            "joints.urdf",
            twin_joint,
            ["lines 7 and 8", "two <joint> elements are named 'j1'"],
        ),
        (
            "links.urdf",
            twin_link,
            ["lines 5 and 10", "two <link> elements are named 'l2'"],
        ),
    ] {
        let p = write(dir.path(), name, &text);
        let mut all = vec![name, "not a valid URDF"];
        all.extend(parts);
        rejected(&reach_urdf(&cell, &p), &all);
    }
    let p = write(dir.path(), "good.urdf", &good);
    let (code, stderr) = run(&reach_urdf(&cell, &p));
    assert_eq!(code, Some(0), "{stderr}");
}

/// A revolute or prismatic joint without `<limit>` is named as such, not with a range the file
/// does not hold.
#[test]
fn urdf_joint_without_limit_is_named() {
    let cell = repo("examples/scenarios/ur5-cell.toml");
    let dir = tempfile::tempdir().unwrap();
    let good = three_joint_urdf("<cylinder radius=\"0.03\" length=\"0.1\"/>", "");
    let limit = "<limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/>";
    for (kind, text) in [
        ("revolute", good.replacen(limit, "", 1)),
        (
            "prismatic",
            good.replacen(limit, "", 1)
                .replacen("type=\"revolute\"", "type=\"prismatic\"", 1),
        ),
    ] {
        let p = write(dir.path(), "nolimit.urdf", &text);
        let e = rejected(
            &reach_urdf(&cell, &p),
            &[
                "nolimit.urdf",
                "line 7: joint 'j1'",
                &format!("is {kind} but has no <limit> element"),
            ],
        );
        assert!(!e.contains("lower=\"0\""), "{e}");
    }
}

/// URDF collision meshes obey the scenario meshes' limit: scaled vertices within 1,000 m of the
/// mesh origin.
#[test]
fn urdf_mesh_scaled_beyond_the_length_limit_is_refused() {
    let cell = repo("examples/scenarios/ur5-cell.toml");
    let dir = tempfile::tempdir().unwrap();
    let vessel = repo("meshes/vessel.stl");
    let mesh = |scale: &str| {
        format!(
            "<mesh filename=\"{}\" scale=\"{scale}\"/>",
            vessel.display()
        )
    };
    for scale in ["1e6 1e6 1e6", "1 1e4 1"] {
        let p = write(dir.path(), "huge.urdf", &three_joint_urdf(&mesh(scale), ""));
        rejected(
            &reach_urdf(&cell, &p),
            &[
                "huge.urdf",
                "link 'base_link'",
                "vessel.stl",
                "more than 1000 m from the mesh origin",
            ],
        );
    }
    // The same mesh at a tenth of its size is read.
    let p = write(
        dir.path(),
        "fine.urdf",
        &three_joint_urdf(&mesh("0.1 0.1 0.1"), ""),
    );
    view_reads(&cell, &p, dir.path());
}

/// Where an output cannot go, the message says why in the user's terms (not the name of a
/// temporary file, nor "File exists"), and a count beyond 2^53 is not quoted as false digits.
#[test]
fn unusable_outputs_and_huge_counts_are_said_plainly() {
    let s = repo("examples/scenarios/paper-2d.toml");
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("no-such-folder").join("p.html");
    let e = rejected(
        &[
            "view".as_ref(),
            s.as_os_str(),
            "-o".as_ref(),
            missing.as_os_str(),
        ],
        &["p.html", "its folder does not exist"],
    );
    assert!(!e.contains(".kinsynth-"), "{e}");
    let file = dir.path().join("a-file");
    std::fs::write(&file, "x").unwrap();
    let e = rejected(
        &[
            "optimize".as_ref(),
            s.as_os_str(),
            "--out".as_ref(),
            file.as_os_str(),
            "--evaluations".as_ref(),
            "8".as_ref(),
        ],
        &["a-file", "exists and is not a folder"],
    );
    assert!(!e.contains("os error"), "{e}");
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "x");
    rejected(
        &[
            "reach".as_ref(),
            s.as_os_str(),
            "--seeds".as_ref(),
            "18446744073709551615".as_ref(),
        ],
        &["--seeds = 1.8446744073709552e19", "from 1 to 1000"],
    );
}

/// `--islands 0` asks for at least one island, and `reach --tree` without `--json` (where the
/// tree would go) is a command-line error.
#[test]
fn island_count_and_tree_without_report_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let cell = repo("examples/scenarios/paper-2d.toml");
    let out = dir.path().join("run");
    rejected(
        &[
            "optimize".as_ref(),
            cell.as_os_str(),
            "--islands".as_ref(),
            "0".as_ref(),
            "--out".as_ref(),
            out.as_os_str(),
        ],
        &["--islands = 0: must be at least 1"],
    );
    let (code, stderr) = run(&["reach".as_ref(), cell.as_os_str(), "--tree".as_ref()]);
    assert_eq!(code, Some(2), "{stderr}");
    assert!(stderr.contains("--json"), "{stderr}");
}

/// Outputs are written together: when one of them cannot be written (a device that refuses
/// the bytes, as a full disk would), the command fails with a one-line error naming it and
/// none of the others is written: not `urdf`'s URDF beside a refused SRDF, not `reach`'s JSON
/// report or trajectories beside a refused SRDF (and a trajectories folder the run would have
/// created is not left behind). The same outputs to regular files are all written.
#[cfg(target_os = "linux")]
#[test]
fn a_refused_output_leaves_the_others_unwritten() {
    let dir = tempfile::tempdir().unwrap();
    let d = write(dir.path(), "d.json", &design("0.3", "[-1, 1]", 2));
    let urdf = dir.path().join("z.urdf");
    rejected(
        &[
            "urdf".as_ref(),
            d.as_os_str(),
            "-o".as_ref(),
            urdf.as_os_str(),
            "--srdf".as_ref(),
            "/dev/full".as_ref(),
        ],
        &["/dev/full", "No space left"],
    );
    assert!(!urdf.exists());
    let cell = repo("examples/scenarios/paper-2d.toml");
    let (json, traj) = (dir.path().join("r.json"), dir.path().join("traj"));
    let reach = |srdf: &Path| -> Vec<std::ffi::OsString> {
        [
            "reach".as_ref(),
            cell.as_os_str(),
            "--json".as_ref(),
            json.as_os_str(),
            "--trajectories".as_ref(),
            traj.as_os_str(),
            "--write-srdf".as_ref(),
            srdf.as_os_str(),
        ]
        .iter()
        .map(|a: &&OsStr| a.to_os_string())
        .collect()
    };
    let args = reach(Path::new("/dev/full"));
    let args: Vec<&OsStr> = args.iter().map(|a| a.as_os_str()).collect();
    rejected(&args, &["/dev/full", "No space left"]);
    assert!(!json.exists() && !traj.exists());
    let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
    assert_eq!(names.len(), 1, "only the design: {names:?}");
    // To regular files, everything is written.
    let srdf = dir.path().join("r.srdf");
    let args = reach(&srdf);
    let args: Vec<&OsStr> = args.iter().map(|a| a.as_os_str()).collect();
    let (code, stderr) = run(&args);
    assert_eq!(code, Some(0), "{stderr}");
    assert!(json.is_file() && srdf.is_file());
    assert_eq!(std::fs::read_dir(&traj).unwrap().count(), 20);
}

/// `urdf` names the robot once for the URDF and the SRDF (MoveIt refuses an SRDF that names
/// another robot): after the URDF file, also with an SRDF elsewhere; with the URDF going to
/// a pipe, after the SRDF file, else `robot` (not `stdout`).
#[cfg(unix)]
#[test]
fn the_urdf_and_its_srdf_name_the_same_robot() {
    let dir = tempfile::tempdir().unwrap();
    let d = write(dir.path(), "d.json", &design("0.3", "[-1, 1]", 2));
    let named = |text: &str| -> String {
        let at = text.find("<robot name=\"").expect("a robot element") + 13;
        text[at..at + text[at..].find('"').unwrap()].to_string()
    };
    let (urdf, other) = (dir.path().join("arm.urdf"), dir.path().join("other.srdf"));
    let args: [&OsStr; 6] = [
        "urdf".as_ref(),
        d.as_os_str(),
        "-o".as_ref(),
        urdf.as_os_str(),
        "--srdf".as_ref(),
        other.as_os_str(),
    ];
    let (code, stderr) = run(&args);
    assert_eq!(code, Some(0), "{stderr}");
    assert_eq!(named(&std::fs::read_to_string(&urdf).unwrap()), "arm");
    assert_eq!(named(&std::fs::read_to_string(&other).unwrap()), "arm");
    let piped = |extra: &[&OsStr]| {
        let out = Command::new(BIN)
            .args([
                "urdf".as_ref(),
                d.as_os_str(),
                "-o".as_ref(),
                "/dev/stdout".as_ref(),
            ])
            .args(extra)
            .stdin(Stdio::null())
            .output()
            .unwrap();
        assert!(out.status.success());
        named(&String::from_utf8_lossy(&out.stdout))
    };
    assert_eq!(piped(&[]), "robot");
    let srdf = dir.path().join("cell_arm.srdf");
    assert_eq!(piped(&["--srdf".as_ref(), srdf.as_os_str()]), "cell_arm");
    assert_eq!(named(&std::fs::read_to_string(&srdf).unwrap()), "cell_arm");
}

/// `edges` bounds its whole work, not only each argument: edges over all `L_max` values and
/// oracle sub-steps over all edges are limited, each refusal one line naming the value.
#[test]
fn edges_bounds_the_product_of_its_counts() {
    let cell = repo("examples/scenarios/paper-2d.toml");
    let edges = |extra: &[&str]| {
        let mut args: Vec<&OsStr> = vec!["edges".as_ref(), cell.as_os_str()];
        args.extend(extra.iter().map(|a| OsStr::new(*a)));
        args.into_iter()
            .map(OsStr::to_os_string)
            .collect::<Vec<_>>()
    };
    let a = edges(&["--count", "100000", "--substeps", "1", "--lmax", "0.1,0.2"]);
    let a: Vec<&OsStr> = a.iter().map(|x| x.as_os_str()).collect();
    rejected(
        &a,
        &[
            "--count = 100000",
            "200000 edges over 2 L_max values",
            "100000",
        ],
    );
    // Without --lmax, three values.
    let a = edges(&["--count", "40000", "--substeps", "1"]);
    let a: Vec<&OsStr> = a.iter().map(|x| x.as_os_str()).collect();
    rejected(&a, &["--count = 40000", "120000 edges over 3 L_max values"]);
    let a = edges(&["--count", "50000", "--substeps", "10000", "--lmax", "0.1"]);
    let a: Vec<&OsStr> = a.iter().map(|x| x.as_os_str()).collect();
    rejected(
        &a,
        &[
            "--substeps = 10000",
            "500000000 oracle sub-steps",
            "200000000",
        ],
    );
}
