//! `kinsynth view` through the command line without a browser: what it writes, and one-line
//! errors naming the file and the field for a reach report that does not belong to the robot or
//! the scenario, with nothing written.

use std::path::{Path, PathBuf};
use std::process::Command;

const BIN: &str = env!("CARGO_BIN_EXE_kinsynth");

fn scenario(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("examples/scenarios/{name}.toml"))
}

fn kinsynth(args: &[&std::ffi::OsStr]) -> std::process::Output {
    Command::new(BIN).args(args).output().unwrap()
}

#[test]
fn view_writes_one_self_contained_page() {
    let dir = tempfile::tempdir().unwrap();
    let page = dir.path().join("glovebox.html");
    let o = kinsynth(&[
        "view".as_ref(),
        scenario("glovebox").as_os_str(),
        "-o".as_ref(),
        page.as_os_str(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let html = std::fs::read_to_string(&page).unwrap();
    assert!(html.starts_with("<!DOCTYPE html>"));
    // Everything inline: no script or stylesheet is fetched from anywhere.
    assert!(!html.contains("<script src"), "an external script");
    assert!(!html.contains("<link "), "an external resource");
    assert!(!html.contains("https://"), "a network address");
    assert!(
        html.contains("three.js authors") || html.contains("REVISION"),
        "three.js inlined"
    );
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        stdout.contains("2 obstacles, 4 tasks, 0 of them with a path"),
        "{stdout}"
    );
}

#[test]
fn a_reach_report_of_another_robot_or_scenario_is_a_one_line_error() {
    let dir = tempfile::tempdir().unwrap();
    let reach = dir.path().join("reach.json");
    let o = kinsynth(&[
        "reach".as_ref(),
        scenario("ur5-cell").as_os_str(),
        "--json".as_ref(),
        reach.as_os_str(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let page = dir.path().join("page.html");
    let cases: [(&str, &[&str], &str); 3] = [
        // Another scenario: 8 targets for 4 tasks.
        (
            "glovebox",
            &[],
            "targets = 8 entries: the scenario has 4 tasks",
        ),
        // Another robot: the UR5 has 6 joints, the largest design 12.
        (
            "ur5-cell",
            &["--urdf", "examples/robots/ur5.urdf"],
            "targets[0].path.points[0] = ",
        ),
        ("ur5-cell", &["--design", "Cargo.toml"], "Cargo.toml"),
    ];
    for (name, extra, message) in cases {
        let mut args: Vec<&std::ffi::OsStr> = vec!["view".as_ref()];
        let s = scenario(name);
        args.push(s.as_os_str());
        args.extend(extra.iter().map(std::ffi::OsStr::new));
        args.extend([
            "--reach".as_ref(),
            reach.as_os_str(),
            "-o".as_ref(),
            page.as_os_str(),
        ]);
        let o = Command::new(BIN)
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .args(&args)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{name} {extra:?}: accepted");
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(err.contains(message), "{name} {extra:?}: {err}");
        assert!(!page.exists(), "nothing is written");
    }
    // `view` of the edited report `v` fails with one line that contains `needles`, writing
    // nothing.
    let refused = |v: &serde_json::Value, needles: &[&str]| {
        std::fs::write(&reach, v.to_string()).unwrap();
        let o = kinsynth(&[
            "view".as_ref(),
            scenario("ur5-cell").as_os_str(),
            "--reach".as_ref(),
            reach.as_os_str(),
            "-o".as_ref(),
            page.as_os_str(),
        ]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success());
        assert_eq!(err.lines().count(), 1, "{err}");
        for n in needles {
            assert!(err.contains(n), "`{n}` missing from {err}");
        }
        assert!(!page.exists());
    };
    // A report whose task points differ from the scenario's.
    let text = std::fs::read_to_string(&reach).unwrap();
    let original: serde_json::Value = serde_json::from_str(&text).unwrap();
    let mut v = original.clone();
    v["targets"][2]["point"][0] = 9.5.into();
    refused(&v, &["reach.json: targets[2].point = [9.5"]);
    // A joint value beyond any axis range (finite, but no robot reaches it).
    let mut v = original.clone();
    let reached = (0..4)
        .find(|&i| v["targets"][i]["path"].is_object())
        .expect("a reached task");
    v["targets"][reached]["path"]["points"][0][0] = (-1e308).into();
    let at = format!("targets[{reached}].path.points[0] = [-1e308");
    refused(&v, &[&at, "each within ±1000"]);
}

/// `reach --tree` adds the planner's tree and changes nothing else; the tree is one tree rooted
/// at node 0 holding every reached task's last path point; `view` refuses a broken tree.
#[test]
fn reach_tree_is_the_planners_tree_and_a_broken_tree_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let (plain, with_tree) = (dir.path().join("plain.json"), dir.path().join("tree.json"));
    let file = scenario("paper-2d");
    for (out, extra) in [(&plain, None), (&with_tree, Some("--tree"))] {
        let mut args: Vec<&std::ffi::OsStr> = vec![
            "reach".as_ref(),
            file.as_os_str(),
            "--json".as_ref(),
            out.as_os_str(),
        ];
        args.extend(extra.map(std::ffi::OsStr::new));
        let o = kinsynth(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    let read = |p: &Path| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
    };
    let (a, mut b) = (read(&plain), read(&with_tree));
    assert!(a.get("tree").is_none(), "no tree unless asked for");
    let tree = b.as_object_mut().unwrap().remove("tree").expect("a tree");
    assert_eq!(a, b, "the tree changes nothing else");
    let parents: Vec<usize> = tree["parents"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p.as_u64().unwrap() as usize)
        .collect();
    let ees = tree["end_effectors"].as_array().unwrap();
    assert_eq!(parents.len(), a["nodes"].as_u64().unwrap() as usize);
    assert_eq!(ees.len(), parents.len());
    assert_eq!(parents[0], 0, "the root is its own parent");
    for start in 0..parents.len() {
        let (mut n, mut steps) = (start, 0);
        while n != 0 {
            n = parents[n];
            steps += 1;
            assert!(
                steps <= parents.len(),
                "node {start} does not lead to the root"
            );
        }
    }
    // Every reached task's end effector is a node of the tree.
    for t in a["targets"].as_array().unwrap() {
        if t["reached"] == true {
            let ee = &t["end_effector"];
            assert!(
                ees.iter().any(|e| (0..3)
                    .all(|k| (e[k].as_f64().unwrap() - ee[k].as_f64().unwrap()).abs() < 1e-12)),
                "task {} ends off the tree",
                t["index"]
            );
        }
    }
    // One parent fewer than nodes.
    let page = dir.path().join("page.html");
    let mut short = read(&with_tree);
    short["tree"]["parents"].as_array_mut().unwrap().pop();
    let short_file = dir.path().join("short.json");
    std::fs::write(&short_file, short.to_string()).unwrap();
    let o = kinsynth(&[
        "view".as_ref(),
        scenario("paper-2d").as_os_str(),
        "--reach".as_ref(),
        short_file.as_os_str(),
        "-o".as_ref(),
        page.as_os_str(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains("short.json: tree.parents = "), "{err}");
    assert!(err.contains("must have one entry per node"), "{err}");
    assert!(!page.exists());
    // A parent that names no node.
    let mut broken = read(&with_tree);
    broken["tree"]["parents"][3] = 1_000_000.into();
    std::fs::write(&with_tree, broken.to_string()).unwrap();
    let o = kinsynth(&[
        "view".as_ref(),
        scenario("paper-2d").as_os_str(),
        "--reach".as_ref(),
        with_tree.as_os_str(),
        "-o".as_ref(),
        page.as_os_str(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains("tree.json: tree.parents[3] = 1000000"),
        "{err}"
    );
    assert!(!page.exists());
}

/// The numbers of a reach report are checked, not only its shape: `R` outside [0, 1] or not
/// the share of its targets reached, an `l_max` of 1.8e19, negative errors, end effectors and
/// tree nodes at 1e308 are one-line errors naming the file, the field and the value, and no
/// page is written.
#[test]
fn a_reach_report_with_numbers_out_of_range_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let file = scenario("paper-2d");
    let report = dir.path().join("reach.json");
    let o = kinsynth(&[
        "reach".as_ref(),
        file.as_os_str(),
        "--json".as_ref(),
        report.as_os_str(),
        "--tree".as_ref(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let good: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    type Edit = fn(&mut serde_json::Value);
    let cases: [(Edit, &str); 9] = [
        (
            |v| v["reachability"] = 1.8e19.into(),
            "reachability = 1.8e19: must lie in [0, 1]",
        ),
        (
            |v| v["reachability"] = 0.5.into(),
            "reachability = 0.5: 10 of its 10 targets are reached",
        ),
        (
            |v| v["l_max"] = 1.8e19.into(),
            "l_max = 1.8e19: must be positive",
        ),
        (|v| v["l_max"] = 0.0.into(), "l_max = 0: must be positive"),
        (
            |v| v["targets"][0]["error"] = (-9.2e18).into(),
            "targets[0].error = -9.2e18: must be finite, not negative",
        ),
        (
            |v| v["targets"][2]["position_error"] = (-1.0).into(),
            "targets[2].position_error = -1",
        ),
        (
            |v| v["targets"][1]["end_effector"][1] = 1e308.into(),
            "targets[1].end_effector = [",
        ),
        (
            |v| v["tree"]["end_effectors"][1][0] = 1e308.into(),
            "tree.end_effectors[1] = [1e308",
        ),
        (
            |v| v["targets"][3]["orientation_error"] = 7.0.into(),
            "targets[3].orientation_error = 7",
        ),
    ];
    let page = dir.path().join("page.html");
    let bad = dir.path().join("bad.json");
    for (edit, part) in cases {
        let mut v = good.clone();
        edit(&mut v);
        std::fs::write(&bad, v.to_string()).unwrap();
        let o = kinsynth(&[
            "view".as_ref(),
            file.as_os_str(),
            "--reach".as_ref(),
            bad.as_os_str(),
            "-o".as_ref(),
            page.as_os_str(),
        ]);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{part}: {stderr}");
        assert_eq!(stderr.lines().count(), 1, "{stderr}");
        assert!(
            stderr.contains(&format!("bad.json: {part}")),
            "`{part}` missing from: {stderr}"
        );
        assert!(!page.exists(), "no page may be written");
    }
    // The report as written is shown.
    let o = kinsynth(&[
        "view".as_ref(),
        file.as_os_str(),
        "--reach".as_ref(),
        report.as_os_str(),
        "-o".as_ref(),
        page.as_os_str(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}
