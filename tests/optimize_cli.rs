//! `kinsynth optimize` through the command line: outputs, resume after a kill, Ctrl-C.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

const BIN: &str = env!("CARGO_BIN_EXE_kinsynth");

fn scenario() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/scenarios/paper-2d.toml")
}

fn optimize(out: &Path, extra: &[&str]) -> Command {
    let mut c = Command::new(BIN);
    c.arg("optimize")
        .arg(scenario())
        .args(["--seed", "3", "--quiet", "--out"])
        .arg(out)
        .args(extra);
    c
}

/// best.json (which holds no wall-clock time).
fn best_json_of(dir: &Path) -> serde_json::Value {
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("best.json")).unwrap()).unwrap();
    assert!(
        v.get("elapsed_s").is_none(),
        "wall-clock time is kept out of best.json"
    );
    v
}

fn generations_in_checkpoint(dir: &Path) -> usize {
    std::fs::read_to_string(dir.join("checkpoint.json"))
        .ok()
        .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok())
        .and_then(|v| v["generation"].as_u64())
        .unwrap_or(0) as usize
}

/// A budget smaller than a generation is exact: `--evaluations 1` makes one evaluation (the
/// first design of the first generation) and says so in the singular.
#[test]
fn a_budget_of_one_evaluation_makes_one() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("one");
    let o = optimize(&out, &["--evaluations", "1", "--recheck-seeds", "0"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let said = String::from_utf8_lossy(&o.stdout);
    assert!(
        said.contains("; 1 evaluation in ") && said.contains("(evaluation budget spent)"),
        "{said}"
    );
    let best: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("best.json")).unwrap()).unwrap();
    assert_eq!(best["evaluations"], 1);
    let history = std::fs::read_to_string(out.join("history.csv")).unwrap();
    let counts: Vec<&str> = history
        .lines()
        .skip(1)
        .filter_map(|r| r.split(',').nth(1))
        .collect();
    assert_eq!(counts, ["1"], "{history}");
}

#[test]
fn writes_every_output_with_the_documented_shape() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let o = optimize(&out, &["--evaluations", "96"]).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let best: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("best.json")).unwrap()).unwrap();
    for key in [
        "design",
        "cost",
        "reachability",
        "links_kept",
        "joints_kept",
        "evaluations",
        "seed",
        "optimizer",
        "checker",
    ] {
        assert!(best.get(key).is_some(), "best.json lacks {key}");
    }
    assert_eq!(best["optimizer"], "ga");
    assert!(
        best.get("elapsed_s").is_none(),
        "wall-clock time is in time.json"
    );
    let time: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("time.json")).unwrap()).unwrap();
    assert!(time["elapsed_s"].as_f64().unwrap() > 0.0, "{time}");
    assert!(time["recheck_s"].as_f64().unwrap() >= 0.0, "{time}");
    let history = std::fs::read_to_string(out.join("history.csv")).unwrap();
    let mut lines = history.lines();
    assert_eq!(
        lines.next(),
        Some("elapsed_s,evaluations,best_cost,best_reachability")
    );
    // Generations of 32 first, then 30 (two elites carried over): 32, 62, 92, and the fourth
    // cut at the budget, after 4 of its 30.
    let rows: Vec<&str> = lines.collect();
    let counts: Vec<&str> = rows.iter().filter_map(|r| r.split(',').nth(1)).collect();
    assert_eq!(counts, ["32", "62", "92", "96"], "one row per generation");
    assert_eq!(best["evaluations"], 96);
    let reach: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("reach.json")).unwrap()).unwrap();
    assert_eq!(reach["reachability"], best["reachability"]);
    // The stream it was planned with, as `reach --json` writes it: replaying best.json gives
    // the same file.
    assert_eq!(reach["stream"], best["stream"]);
    assert!(std::fs::read_to_string(out.join("convergence.svg"))
        .unwrap()
        .starts_with("<svg"));
    let urdf = std::fs::read_to_string(out.join("robot.urdf")).unwrap();
    assert!(urdf.contains("<robot") && urdf.contains("j2_ry"));
    // A trajectory pair per reached task.
    let reached = reach["targets"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|t| t["reached"].as_bool().unwrap())
        .count();
    let files = std::fs::read_dir(out.join("trajectories")).unwrap().count();
    assert_eq!(files, 2 * reached);
    // best.json is accepted by `reach --design`, and gives the same R with the same stream.
    let replayed = dir.path().join("replayed.json");
    let o = Command::new(BIN)
        .args(["reach", "--design"])
        .arg(out.join("best.json"))
        .arg(scenario())
        .arg("--json")
        .arg(&replayed)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(
        std::fs::read_to_string(&replayed).unwrap(),
        std::fs::read_to_string(out.join("reach.json")).unwrap(),
        "the replay's report is the run's reach.json"
    );
    // The baseline flag selects ASA with node-only checks at π/40.
    let base = dir.path().join("baseline");
    let o = optimize(&base, &["--baseline", "--evaluations", "32"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let b = best_json_of(&base);
    assert_eq!(b["optimizer"], "asa");
    assert_eq!(b["checker"], "discrete");
    assert!((b["l_max"].as_f64().unwrap() - std::f64::consts::PI / 40.0).abs() < 1e-12);
    // ... planned with the paper's RRT: no backward trees, a fixed budget.
    assert_eq!(b["planner"]["postures"], 0, "{}", b["planner"]);
    assert_eq!(b["planner"]["budget_growth"], 1, "{}", b["planner"]);
}

#[test]
fn a_killed_run_resumes_to_the_same_result() {
    let dir = tempfile::tempdir().unwrap();
    let whole = dir.path().join("whole");
    let budget = ["--evaluations", "320", "--checkpoint-interval", "0"];
    let o = optimize(&whole, &budget).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));

    let killed = dir.path().join("killed");
    let mut child = optimize(&killed, &budget)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while generations_in_checkpoint(&killed) < 3 {
        assert!(start.elapsed() < Duration::from_secs(120), "no checkpoint");
        std::thread::sleep(Duration::from_millis(5));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let at_kill = generations_in_checkpoint(&killed);
    assert!(
        at_kill < 10,
        "killed before the end (generation {at_kill} of 10)"
    );

    let o = Command::new(BIN)
        .args(["optimize", "--quiet", "--resume"])
        .arg(&killed)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(best_json_of(&killed), best_json_of(&whole));
    let rows = |d: &Path| {
        std::fs::read_to_string(d.join("history.csv"))
            .unwrap()
            .lines()
            .count()
    };
    assert_eq!(rows(&killed), rows(&whole));
}

/// Ctrl-C (SIGINT), and SIGTERM and SIGHUP (what Slurm at a job's time limit, `timeout`,
/// `docker stop` and a closed terminal send), stop a run within its generation: it writes its
/// results, removes its lock and exits cleanly.
#[test]
fn ctrl_c_writes_the_best_design_so_far() {
    for signal in ["-INT", "-TERM", "-HUP"] {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("interrupted");
        let mut child = optimize(&out, &["--time-limit", "600", "--checkpoint-interval", "0"])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        let start = Instant::now();
        while generations_in_checkpoint(&out) < 1 {
            assert!(start.elapsed() < Duration::from_secs(120), "no checkpoint");
            std::thread::sleep(Duration::from_millis(5));
        }
        let status = Command::new("kill")
            .args([signal, &child.id().to_string()])
            .status()
            .unwrap();
        assert!(status.success());
        let exit = child.wait().unwrap();
        assert!(
            exit.success(),
            "{signal}: a stopped run ends cleanly after writing its results ({exit})"
        );
        let best = best_json_of(&out);
        assert_eq!(best["stopped"], "interrupted", "{signal}");
        assert!(best["design"]["links"].as_array().unwrap().len() == 8);
        assert!(out.join("reach.json").exists(), "{signal}");
        assert!(
            !out.join(".kinsynth.lock").exists(),
            "{signal}: the lock is removed"
        );
    }
}

/// `--evaluations` on the command line replaces both of the scenario's budgets: the scenario's
/// time limit (here a microsecond) does not cut it short, so the result depends on the seed
/// only; without a budget on the command line the scenario's time limit holds (a new run still
/// evaluates its first design).
#[test]
fn an_evaluation_budget_replaces_the_scenario_time_limit() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(scenario()).unwrap();
    assert!(text.contains("\ntime_limit = 60.0\n"));
    let fast = dir.path().join("short-limit.toml");
    std::fs::write(
        &fast,
        text.replace("\ntime_limit = 60.0\n", "\ntime_limit = 0.000001\n"),
    )
    .unwrap();
    // The evaluations of the run.
    let run = |out: &Path, extra: &[&str]| {
        let o = Command::new(BIN)
            .arg("optimize")
            .arg(&fast)
            .args(["--seed", "3", "--quiet", "--recheck-seeds", "0", "--out"])
            .arg(out)
            .args(extra)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let best: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("best.json")).unwrap()).unwrap();
        best["evaluations"].as_u64()
    };
    // Generations of 32, then 30: 96 evaluations end within the fourth, at 96 exactly.
    assert_eq!(
        run(&dir.path().join("budget"), &["--evaluations", "96"]),
        Some(96)
    );
    let limited = run(&dir.path().join("limited"), &[]);
    assert!(
        limited.is_some_and(|n| (1..96).contains(&n)),
        "the scenario's time limit did not stop it: {limited:?}"
    );
}

/// A new run in a folder that holds an earlier run's results says that it replaces them; a
/// first run says nothing of the kind.
#[test]
fn a_new_run_in_a_used_folder_says_it_replaces_the_results() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    for first in [true, false] {
        let o = optimize(&out, &["--evaluations", "4"]).output().unwrap();
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(o.status.success(), "{stderr}");
        assert_eq!(
            stderr.contains("replacing the results of an earlier run"),
            !first,
            "{stderr}"
        );
    }
}

/// `optimize` puts its results in place together: when one cannot be written (here its SRDF,
/// a link to `/dev/full`, as on a full disk), the run fails with a one-line error naming it
/// and none of the other results is written (no `best.json`, no trajectories, no temporary
/// file left), where the same run into an empty folder writes them all.
#[cfg(target_os = "linux")]
#[test]
fn a_result_that_cannot_be_written_leaves_the_others_unwritten() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    std::fs::create_dir(&out).unwrap();
    std::os::unix::fs::symlink("/dev/full", out.join("robot.srdf")).unwrap();
    let o = optimize(&out, &["--evaluations", "20", "--recheck-seeds", "1"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    let error: Vec<&str> = stderr.lines().filter(|l| l.starts_with("error")).collect();
    assert_eq!(error.len(), 1, "{stderr}");
    assert!(
        error[0].contains("robot.srdf") && error[0].contains("No space left"),
        "{stderr}"
    );
    let mut left: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    left.sort();
    // The checkpoint is written apart from the results (it lets the run be resumed).
    assert_eq!(left, ["checkpoint.json", "robot.srdf"], "{stderr}");
    std::fs::remove_file(out.join("robot.srdf")).unwrap();
    let o = optimize(&out, &["--evaluations", "20", "--recheck-seeds", "1"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for f in [
        "best.json",
        "robot.urdf",
        "robot.srdf",
        "reach.json",
        "report.html",
    ] {
        assert!(out.join(f).is_file(), "{f}");
    }
}

/// A run whose checkpoint could not be read back is refused before it starts: a GA's
/// population (or a swarm) times the design's free variables, over all islands, is limited
/// (paper-3d has 56: 10,000 designs make 560,000, above the 500,000 a checkpoint holds), with
/// one line naming the scenario, the field and the value, and no folder left behind; ASA, which
/// keeps a few designs, runs.
#[test]
fn a_population_a_checkpoint_cannot_hold_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/scenarios/paper-3d.toml"),
    )
    .unwrap();
    assert!(text.contains("\npopulation = 32\n"));
    let scenario = |population: usize| {
        let p = dir.path().join(format!("p{population}.toml"));
        let edited = text.replace(
            "\npopulation = 32\n",
            &format!("\npopulation = {population}\n"),
        );
        std::fs::write(&p, edited).unwrap();
        p
    };
    let run = |s: &Path, extra: &[&str]| {
        Command::new(BIN)
            .arg("optimize")
            .arg(s)
            .args([
                "--quiet",
                "--evaluations",
                "2",
                "--recheck-seeds",
                "0",
                "--out",
            ])
            .arg(dir.path().join("out/run"))
            .args(extra)
            .output()
            .unwrap()
    };
    let refused = |o: std::process::Output, parts: &[&str]| {
        let stderr = String::from_utf8_lossy(&o.stderr).into_owned();
        assert_eq!(o.status.code(), Some(1), "{stderr}");
        assert_eq!(stderr.lines().count(), 1, "{stderr}");
        // Refused before it wrote anything: the folders it created are gone again.
        assert!(!dir.path().join("out").exists(), "{stderr}");
        for p in parts {
            assert!(stderr.contains(p), "`{p}` missing from {stderr}");
        }
    };
    let big = scenario(10_000);
    refused(
        run(&big, &[]),
        &[
            "p10000.toml",
            "optimizer.population = 10000",
            "56 free variables make 560000",
            "500000",
        ],
    );
    refused(run(&big, &["--optimizer", "pso"]), &["560000"]);
    let half = scenario(5_000);
    refused(
        run(&half, &["--islands", "2"]),
        &[
            "optimizer.population = 5000",
            "in each of 2 islands",
            "560000",
        ],
    );
    // Through `..`, a folder that existed stays, and nothing is removed.
    let keep = dir.path().join("keep");
    std::fs::create_dir(&keep).unwrap();
    let o = Command::new(BIN)
        .arg("optimize")
        .arg(&big)
        .args(["--quiet", "--evaluations", "2", "--out"])
        .arg(dir.path().join("new/../keep"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert!(keep.is_dir());
    std::fs::remove_dir(&keep).unwrap();
    let _ = std::fs::remove_dir(dir.path().join("new"));
    let o = run(&half, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = run(&big, &["--optimizer", "asa"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}
