//! Experiments in slices (`--shard K/N`) and their merge: the slices cover every workspace
//! once, and the merged tables equal the unsharded experiment's.

use kinsynth::optimize::experiment::{merge, run_experiment, ExperimentSpec, Shard};
use kinsynth::scenario::preset::Preset;
use std::path::Path;

fn spec() -> ExperimentSpec {
    ExperimentSpec {
        preset: Preset::Paper3d,
        runs: 3,
        // Far more than the runs take: they stop at their evaluation budget, so every result
        // but the times depends on the seeds only.
        time_limit: 600.0,
        evaluations: Some(48),
        seed: 40,
    }
}

fn read(p: &Path) -> String {
    std::fs::read_to_string(p).unwrap()
}

/// runs.csv without the two columns of seconds (time to R = 1, elapsed).
fn without_times(runs_csv: &str) -> Vec<String> {
    runs_csv
        .lines()
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            assert_eq!(f.len(), 9, "{l}");
            [&f[..3], &f[4..8]].concat().join(",")
        })
        .collect()
}

/// Workspace `w` has the seed `seed + w`: a first seed whose workspaces would wrap past the
/// largest seed to 0 is refused, naming the flag and the value.
#[test]
fn every_workspace_seed_must_exist() {
    for (seed, runs, ok) in [
        (u64::MAX, 1, true),
        (u64::MAX, 2, false),
        (u64::MAX - 9, 10, true),
        (u64::MAX - 8, 10, false),
    ] {
        let r = ExperimentSpec {
            seed,
            runs,
            ..spec()
        }
        .validate();
        assert_eq!(r.is_ok(), ok, "{seed} {runs}: {r:?}");
        if let Err(e) = r {
            let e = e.to_string();
            assert!(e.contains(&format!("--seed = {seed}")), "{e}");
        }
    }
}

/// An experiment runs at least one workspace and at most 100,000 (`--runs 0` printed medians
/// of nothing).
#[test]
fn runs_must_be_from_1_to_the_limit() {
    for (runs, ok) in [(0, false), (1, true), (100_000, true), (100_001, false)] {
        let r = ExperimentSpec { runs, ..spec() }.validate();
        assert_eq!(r.is_ok(), ok, "{runs}: {r:?}");
        if let Err(e) = r {
            let e = e.to_string();
            assert!(
                e.contains(&format!("--runs = {runs}")) && e.contains("from 1 to 100000"),
                "{e}"
            );
        }
    }
}

#[test]
fn shards_parse_and_cover_every_workspace_once() {
    assert_eq!(
        "2/4".parse::<Shard>().unwrap(),
        Shard { index: 2, count: 4 }
    );
    for bad in ["0/4", "5/4", "1/0", "2", "a/b", "1/-2", ""] {
        let e = bad.parse::<Shard>().unwrap_err().to_string();
        assert!(e.starts_with(&format!("--shard = {bad}:")), "{e}");
    }
    for runs in [0, 1, 3, 10, 11] {
        for n in 1..=12 {
            let all: Vec<usize> = (1..=n)
                .flat_map(|k| Shard { index: k, count: n }.workspaces(runs))
                .collect();
            assert_eq!(
                all,
                (0..runs).collect::<Vec<_>>(),
                "{runs} runs in {n} slices"
            );
        }
    }
}

#[test]
fn two_shards_merge_into_the_unsharded_tables() {
    let dir = tempfile::tempdir().unwrap();
    let whole = dir.path().join("whole");
    run_experiment(&spec(), Shard::WHOLE, &whole, &mut |_| {}).unwrap();
    let (a, b) = (dir.path().join("a"), dir.path().join("b"));
    run_experiment(&spec(), Shard { index: 1, count: 2 }, &a, &mut |_| {}).unwrap();
    run_experiment(&spec(), Shard { index: 2, count: 2 }, &b, &mut |_| {}).unwrap();
    assert!(a.join("workspace0").is_dir() && !a.join("workspace1").exists());
    assert!(b.join("workspace1").is_dir() && b.join("workspace2").is_dir());

    let merged = dir.path().join("merged");
    let records = merge(&[b.clone(), a.clone()], &merged).unwrap();
    assert_eq!(records.len(), 3);
    assert_eq!(
        without_times(&read(&merged.join("runs.csv"))),
        without_times(&read(&whole.join("runs.csv")))
    );
    assert_eq!(
        read(&merged.join("experiment.json")),
        read(&whole.join("experiment.json"))
    );
    // The times differ between two runs of the same experiment; merging the whole experiment's
    // own folder reproduces its tables byte for byte.
    let again = dir.path().join("again");
    merge(std::slice::from_ref(&whole), &again).unwrap();
    for f in ["runs.csv", "curves.csv", "curves.svg"] {
        assert_eq!(read(&again.join(f)), read(&whole.join(f)), "{f}");
    }
    // The seconds come from each run's time.json: a bad or missing one is refused, naming it.
    let time = whole.join("workspace0/method0/time.json");
    std::fs::write(&time, r#"{"elapsed_s": -1.0}"#).unwrap();
    let e = merge(std::slice::from_ref(&whole), &dir.path().join("bad"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains(&time.display().to_string()) && e.contains("elapsed_s = -1"),
        "{e}"
    );
    std::fs::remove_file(&time).unwrap();
    let e = merge(std::slice::from_ref(&whole), &dir.path().join("bad"))
        .unwrap_err()
        .to_string();
    assert!(e.contains(&time.display().to_string()), "{e}");
    assert!(
        !dir.path().join("bad").join("runs.csv").exists(),
        "nothing is written"
    );

    // A missing slice, a slice given twice and a slice of another experiment are refused.
    let e = merge(std::slice::from_ref(&a), &dir.path().join("m1"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("workspace 1 of 3 is in none of them"), "{e}");
    let e = merge(&[a.clone(), a.clone(), b.clone()], &dir.path().join("m2"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("workspace 0 is also in"), "{e}");
    let other = dir.path().join("other");
    let mut s = spec();
    s.seed = 41;
    s.runs = 1;
    run_experiment(&s, Shard::WHOLE, &other, &mut |_| {}).unwrap();
    let e = merge(&[a, b, other.clone()], &dir.path().join("m3"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains(&other.join("experiment.json").display().to_string())
            && e.contains("is not the experiment of"),
        "{e}"
    );
    // A manifest's slice out of its domain is refused before its workspaces are computed
    // (`N = 0` divided by zero).
    let manifest = other.join("experiment.json");
    let text = read(&manifest);
    for (bad, shown) in [("0", "1/0"), ("100001", "1/100001")] {
        let mut m: serde_json::Value = serde_json::from_str(&text).unwrap();
        m["shard"]["count"] = serde_json::json!(bad.parse::<u64>().unwrap());
        std::fs::write(&manifest, serde_json::to_string(&m).unwrap()).unwrap();
        let e = merge(std::slice::from_ref(&other), &dir.path().join("m4"))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains(&manifest.display().to_string())
                && e.contains(&format!("shard = {shown}: N must lie in 1..=100000")),
            "{e}"
        );
    }
}

/// Runs `kinsynth merge` on `dirs` into `out`: it must fail with one line `error: …` holding
/// every part, and write nothing into `out`.
fn merge_refused(dirs: &[&Path], out: &Path, parts: &[&str]) {
    let before = std::fs::read_dir(out).map_or(0, |d| d.count());
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_kinsynth"))
        .arg("merge")
        .args(dirs)
        .arg("--out")
        .arg(out)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    assert_eq!(stderr.lines().count(), 1, "one line: {stderr}");
    assert!(stderr.len() < 400, "a short line: {stderr}");
    for p in parts {
        assert!(stderr.contains(p), "`{p}` missing from: {stderr}");
    }
    let after = std::fs::read_dir(out).map_or(0, |d| d.count());
    assert_eq!(
        before,
        after,
        "nothing may be written into {}",
        out.display()
    );
}

/// Two slices of a small experiment.
fn two_slices(dir: &Path) -> (std::path::PathBuf, std::path::PathBuf) {
    let s = ExperimentSpec { runs: 2, ..spec() };
    let (a, b) = (dir.join("a"), dir.join("b"));
    run_experiment(&s, Shard { index: 1, count: 2 }, &a, &mut |_| {}).unwrap();
    run_experiment(&s, Shard { index: 2, count: 2 }, &b, &mut |_| {}).unwrap();
    (a, b)
}

/// The slices' folders are only read: `merge --out` naming one of them (or a folder inside
/// one, or one through a link) is refused before anything is written; a folder holding them is
/// fine.
#[test]
fn merge_never_writes_into_a_slice() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = two_slices(dir.path());
    let manifest = read(&a.join("experiment.json"));
    merge_refused(&[&a, &b], &a, &["--out = ", "is also the slice folder"]);
    merge_refused(&[&a, &b], &b.join("../a"), &["is also the slice folder"]);
    merge_refused(
        &[&a, &b],
        &a.join("merged"),
        &["lies inside the slice folder"],
    );
    merge_refused(
        &[&a, &b],
        &b.join("workspace1"),
        &["lies inside the slice folder"],
    );
    #[cfg(unix)]
    {
        let link = dir.path().join("link");
        std::os::unix::fs::symlink(&a, &link).unwrap();
        merge_refused(&[&a, &b], &link, &["is also the slice folder"]);
    }
    assert_eq!(read(&a.join("experiment.json")), manifest);
    assert!(!a.join("merged").exists());
    merge(&[a, b], dir.path()).unwrap();
    assert!(dir.path().join("runs.csv").is_file());
}

/// Every number `merge` reads from a run (best.json, time.json, checkpoint.json) is checked:
/// out of its range, it is a one-line error naming the file, the field and the value, and
/// nothing is merged. Slices that differ name the setting and both values, and a manifest's
/// fields are named as the file names them, in short lines.
#[test]
fn merge_refuses_numbers_out_of_range_naming_file_field_and_value() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = two_slices(dir.path());
    let out = dir.path().join("out");
    let run = a.join("workspace0/method0");
    let edit = |file: &str, f: &dyn Fn(&mut serde_json::Value)| {
        let p = run.join(file);
        let text = read(&p);
        let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
        f(&mut v);
        std::fs::write(&p, serde_json::to_string(&v).unwrap()).unwrap();
        text
    };
    type Edit = fn(&mut serde_json::Value);
    let cases: [(&str, Edit, &str); 15] = [
        // Within its range, but not the design's.
        (
            "best.json",
            |v| v["links_kept"] = 0.into(),
            "best.json: links_kept = 0: the design keeps",
        ),
        // Another method's or workspace's results in this run's place.
        (
            "best.json",
            |v| v["optimizer"] = "asa".into(),
            "best.json: optimizer = asa: workspace 0, method 0",
        ),
        (
            "best.json",
            |v| v["checker"] = "discrete".into(),
            "best.json: checker = discrete: workspace 0, method 0",
        ),
        (
            "best.json",
            |v| v["seed"] = 12345.into(),
            "best.json: seed = 12345: workspace 0, method 0",
        ),
        (
            "best.json",
            |v| v["reachability"] = 1e308.into(),
            "best.json: reachability = 1e308: must lie in [0, 1]",
        ),
        (
            "best.json",
            |v| v["reachability"] = (-0.5).into(),
            "reachability = -0.5",
        ),
        (
            "best.json",
            |v| v["cost"] = (-1.0).into(),
            "best.json: cost = -1: must be finite and not negative",
        ),
        (
            "best.json",
            |v| v["links_kept"] = 1000.into(),
            "best.json: links_kept = 1000",
        ),
        (
            "best.json",
            |v| v["evaluations"] = 49.into(),
            "best.json: evaluations = 49: the experiment makes at most 48",
        ),
        (
            "best.json",
            |v| v["design"]["links"][0]["a"] = 1e300.into(),
            "best.json: design.links[0].a = 1e300",
        ),
        (
            "time.json",
            |v| v["elapsed_s"] = 1e308.into(),
            "time.json: elapsed_s = 1e308",
        ),
        (
            "checkpoint.json",
            |v| v["history"][0]["elapsed_s"] = 1e300.into(),
            "checkpoint.json: history[0].elapsed_s = 1e300",
        ),
        (
            "checkpoint.json",
            |v| v["history"][0]["best_reachability"] = 2.0.into(),
            "checkpoint.json: history[0].best_reachability = 2",
        ),
        (
            "checkpoint.json",
            |v| v["history"][0]["best_cost"] = (-3.0).into(),
            "checkpoint.json: history[0].best_cost = -3",
        ),
        // In its range, but not what the run wrote: its checksum tells.
        (
            "checkpoint.json",
            |v| v["history"][0]["best_cost"] = 1.5.into(),
            "checkpoint.json: checksum = fnv1a64:",
        ),
    ];
    for (file, f, part) in cases {
        let original = edit(file, &f);
        merge_refused(&[&a, &b], &out, &[part]);
        assert!(!out.exists(), "{part}: nothing may be written");
        std::fs::write(run.join(file), original).unwrap();
    }
    // A checkpoint without a checksum (an older version's) is merged, with the warning a
    // resume gives.
    let original = edit("checkpoint.json", &|v| {
        v.as_object_mut().unwrap().remove("checksum");
    });
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_kinsynth"))
        .arg("merge")
        .args([&a, &b])
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    assert!(
        stderr.contains("checkpoint.json: the checkpoint records no checksum"),
        "{stderr}"
    );
    std::fs::write(run.join("checkpoint.json"), original).unwrap();
    std::fs::remove_dir_all(&out).unwrap();
    // An --out that is a file, not a folder, is named as such.
    let file = dir.path().join("file");
    std::fs::write(&file, "x").unwrap();
    merge_refused(
        &[&a, &b],
        &file,
        &["file: cannot write: exists and is not a folder"],
    );
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "x");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_kinsynth"))
        .args([
            "experiment",
            "paper-2d",
            "--runs",
            "1",
            "--evaluations",
            "10",
            "--out",
        ])
        .arg(&file)
        .output()
        .unwrap();
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(
        e.contains("file: cannot write: exists and is not a folder"),
        "{e}"
    );
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "x");
    // Slices of different experiments: the setting and both values, no debug output.
    let m = a.join("experiment.json");
    let original = read(&m);
    let set = |f: &dyn Fn(&mut serde_json::Value)| {
        let mut v: serde_json::Value = serde_json::from_str(&original).unwrap();
        f(&mut v);
        std::fs::write(&m, serde_json::to_string(&v).unwrap()).unwrap();
    };
    set(&|v| v["spec"]["time_limit"] = 6.0.into());
    merge_refused(
        &[&a, &b],
        &out,
        &[
            "b/experiment.json: spec.time_limit = 600: is not the experiment of",
            "(time_limit = 6)",
        ],
    );
    set(&|v| v["spec"]["time_limit"] = (-1.0).into());
    merge_refused(
        &[&a, &b],
        &out,
        &["a/experiment.json: spec.time_limit = -1: must be positive"],
    );
    set(&|v| v["spec"]["runs"] = 0.into());
    merge_refused(
        &[&a, &b],
        &out,
        &["a/experiment.json: spec.runs = 0: must be from 1"],
    );
    set(&|v| v["spec"]["runs"] = 100_000.into());
    merge_refused(
        &[&a, &b],
        &out,
        &[
            "workspaces = [0]",
            "holds [0, 1, 2, 3, 4, … and 49995 more]",
        ],
    );
    std::fs::write(&m, &original).unwrap();
    merge(&[a, b], &out).unwrap();
}
