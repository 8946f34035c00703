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
