//! Joint trajectories from reachability paths, keyed by URDF joint names so they replay on the
//! exported (or imported) URDF.
//!
//! A path is a list of configurations from home to a task ([`PathReport`]). Its timing is the
//! cumulative path length in joint space: `t_k = s_k / s_N` with `s_k = Σ_{j≤k} ‖q_j − q_{j−1}‖`
//! (Euclidean over all joints, radians and metres alike), so `t` runs from 0 at home to 1 at the
//! task. The ROS form (`trajectory_msgs/JointTrajectory`) scales `t` to seconds at
//! [`SECONDS_PER_UNIT`] per unit of path length: `time_from_start = t · s_N · SECONDS_PER_UNIT`
//! (1 s per radian, or per metre). A path whose points all coincide spreads its points evenly
//! over `t` and lasts 0 s; a one-point path (a task reached by the home node itself) is a single
//! row at `t = 0`.
//!
//! Files per reached task `i`: `task_{i}.csv` (header `t,{joint names…}`, one row per path
//! point) and `task_{i}.json` (`joint_names`, `points[].positions`, `points[].time_from_start`
//! as `{secs, nsecs}`, plus empty `velocities`, `accelerations` and `effort`).

use crate::error::{Error, Result};
use crate::planning::{PathReport, ReachReport};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Seconds per unit (radian or metre) of joint-space path length in the ROS form.
pub const SECONDS_PER_UNIT: f64 = 1.0;

/// A timed joint trajectory.
#[derive(Clone, Debug, PartialEq)]
pub struct Trajectory {
    /// Joint names, one per column.
    pub joint_names: Vec<String>,
    /// Normalised time of each point, from 0 to 1 by cumulative joint-space path length.
    pub t: Vec<f64>,
    /// Joint values of each point.
    pub points: Vec<Vec<f64>>,
    /// Total joint-space path length `s_N` (radians and metres).
    pub length: f64,
}

/// `{secs, nsecs}` of a ROS duration.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct RosDuration {
    /// Whole seconds.
    pub secs: i32,
    /// Nanoseconds, `0 ≤ nsecs < 10⁹`.
    pub nsecs: u32,
}

impl RosDuration {
    /// The duration of `seconds` (not negative), rounded to the nanosecond.
    pub fn from_secs_f64(seconds: f64) -> Self {
        let total = (seconds.max(0.0) * 1e9).round() as i64;
        RosDuration {
            secs: (total / 1_000_000_000) as i32,
            nsecs: (total % 1_000_000_000) as u32,
        }
    }

    /// The duration in seconds.
    pub fn as_secs_f64(&self) -> f64 {
        f64::from(self.secs) + f64::from(self.nsecs) * 1e-9
    }
}

/// One point of a ROS `trajectory_msgs/JointTrajectoryPoint`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RosPoint {
    /// Joint values, in the order of `joint_names`.
    pub positions: Vec<f64>,
    /// Empty: the path carries no velocities.
    pub velocities: Vec<f64>,
    /// Empty.
    pub accelerations: Vec<f64>,
    /// Empty.
    pub effort: Vec<f64>,
    /// Time from the start of the trajectory.
    pub time_from_start: RosDuration,
}

/// A ROS `trajectory_msgs/JointTrajectory` (without its header).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RosJointTrajectory {
    /// Joint names.
    pub joint_names: Vec<String>,
    /// The points, in time order.
    pub points: Vec<RosPoint>,
}

impl Trajectory {
    /// Times a path by cumulative joint-space length (see the module documentation).
    pub fn from_path(path: &PathReport) -> Self {
        let mut s = Vec::with_capacity(path.points.len());
        let mut acc = 0.0;
        for (k, q) in path.points.iter().enumerate() {
            if k > 0 {
                let prev = &path.points[k - 1];
                acc += q
                    .iter()
                    .zip(prev)
                    .map(|(a, b)| (a - b) * (a - b))
                    .sum::<f64>()
                    .sqrt();
            }
            s.push(acc);
        }
        let n = s.len();
        let t = if acc > 0.0 {
            let mut t: Vec<f64> = s.iter().map(|v| v / acc).collect();
            if let Some(last) = t.last_mut() {
                *last = 1.0;
            }
            t
        } else if n > 1 {
            (0..n).map(|k| k as f64 / (n - 1) as f64).collect()
        } else {
            vec![0.0; n]
        };
        Trajectory {
            joint_names: path.joint_names.clone(),
            t,
            points: path.points.clone(),
            length: acc,
        }
    }

    /// Duration of the ROS form: `length · SECONDS_PER_UNIT`.
    pub fn duration(&self) -> f64 {
        self.length * SECONDS_PER_UNIT
    }

    /// The CSV form: header `t,{joint names}`, one row per point, numbers in Rust's shortest
    /// round-trip notation.
    pub fn to_csv(&self) -> String {
        let mut out = String::from("t");
        for n in &self.joint_names {
            out.push(',');
            out.push_str(n);
        }
        out.push('\n');
        for (t, q) in self.t.iter().zip(&self.points) {
            out.push_str(&t.to_string());
            for v in q {
                out.push(',');
                out.push_str(&v.to_string());
            }
            out.push('\n');
        }
        out
    }

    /// The ROS `JointTrajectory` form, `t = 1` at [`Trajectory::duration`].
    pub fn to_ros(&self) -> RosJointTrajectory {
        let d = self.duration();
        RosJointTrajectory {
            joint_names: self.joint_names.clone(),
            points: self
                .t
                .iter()
                .zip(&self.points)
                .map(|(t, q)| RosPoint {
                    positions: q.clone(),
                    velocities: Vec::new(),
                    accelerations: Vec::new(),
                    effort: Vec::new(),
                    time_from_start: RosDuration::from_secs_f64(t * d),
                })
                .collect(),
        }
    }

    /// The ROS form as pretty-printed JSON.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(&self.to_ros()).expect("a trajectory always serialises")
    }
}

/// The two files of task `index`'s trajectory in `dir`: `task_{index}.csv` and
/// `task_{index}.json`.
pub fn trajectory_files(dir: &Path, index: usize) -> [PathBuf; 2] {
    [
        dir.join(format!("task_{index}.csv")),
        dir.join(format!("task_{index}.json")),
    ]
}

/// Checks, before any work, that the trajectory files of the tasks `indices` can be written in
/// `dir` ([`crate::io::check_output_file`] for each; `dir` itself may not exist yet).
pub fn check_trajectory_files(dir: &Path, indices: impl IntoIterator<Item = usize>) -> Result<()> {
    crate::io::check_output_dir(dir)?;
    if !dir.is_dir() {
        return Ok(()); // created empty: nothing in it can be in the way
    }
    for i in indices {
        for f in trajectory_files(dir, i) {
            crate::io::check_output_file(&f)?;
        }
    }
    Ok(())
}

/// Writes `task_{index}.csv` and `task_{index}.json` into `dir` (created if missing) for every
/// reached task of `report` with a path, atomically, and removes those of the other tasks left
/// by an earlier run; returns the files written.
pub fn write_trajectories(report: &ReachReport, dir: &Path) -> Result<Vec<PathBuf>> {
    let mut staged = crate::io::Staged::default();
    let written = stage_trajectories(report, dir, &mut staged)?;
    staged.commit()?;
    Ok(written)
}

/// As [`write_trajectories`], staged in `staged` with a caller's other outputs (`dir` is
/// created now); returns the files it will write.
pub fn stage_trajectories(
    report: &ReachReport,
    dir: &Path,
    staged: &mut crate::io::Staged,
) -> Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir).map_err(|source| Error::Write {
        path: dir.to_path_buf(),
        source,
    })?;
    // Every name is checked before the first file is written: nothing half-written.
    check_trajectory_files(dir, report.targets.iter().map(|t| t.index))?;
    let mut written = Vec::new();
    for t in &report.targets {
        let Some(path) = &t.path else {
            // An earlier run's files of a task this report has no path for would be taken
            // for this run's: they go.
            for file in trajectory_files(dir, t.index) {
                staged.remove_stale(&file);
            }
            continue;
        };
        let traj = Trajectory::from_path(path);
        let [csv, json] = trajectory_files(dir, t.index);
        staged.add(&csv, traj.to_csv().as_bytes())?;
        staged.add(&json, traj.to_json().as_bytes())?;
        written.push(csv);
        written.push(json);
    }
    Ok(written)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn path() -> PathReport {
        PathReport {
            joint_names: vec!["j1_rz".into(), "j2_tx".into()],
            points: vec![vec![0.0, 0.0], vec![3.0, 4.0], vec![3.0, 9.0]],
        }
    }

    #[test]
    fn time_follows_cumulative_joint_space_length() {
        let tr = Trajectory::from_path(&path());
        assert_eq!(tr.t, vec![0.0, 0.5, 1.0]);
        assert_eq!(tr.length, 10.0);
        let csv = tr.to_csv();
        assert_eq!(csv, "t,j1_rz,j2_tx\n0,0,0\n0.5,3,4\n1,3,9\n");
        let ros = tr.to_ros();
        assert_eq!(
            ros.points[1].time_from_start,
            RosDuration { secs: 5, nsecs: 0 }
        );
        assert_eq!(
            ros.points[2].time_from_start.as_secs_f64(),
            10.0 * SECONDS_PER_UNIT
        );
    }

    #[test]
    fn a_path_at_home_spreads_evenly_and_lasts_nothing() {
        let p = PathReport {
            joint_names: vec!["a".into()],
            points: vec![vec![0.5], vec![0.5]],
        };
        let tr = Trajectory::from_path(&p);
        assert_eq!(tr.t, vec![0.0, 1.0]);
        assert_eq!(tr.duration(), 0.0);
        let one = PathReport {
            joint_names: vec!["a".into()],
            points: vec![vec![0.5]],
        };
        let tr = Trajectory::from_path(&one);
        assert_eq!(tr.to_csv(), "t,a\n0,0.5\n");
    }

    #[test]
    fn only_reached_tasks_get_files() {
        let dir = tempfile::tempdir().unwrap();
        let target = |index, path: Option<PathReport>| crate::planning::TargetReport {
            index,
            point: [0.0; 3],
            reached: path.is_some(),
            end_effector: [0.0; 3],
            error: 0.0,
            path,
            ..crate::planning::TargetReport::default()
        };
        let report = ReachReport {
            tree: None,
            reachability: 0.5,
            checker: "segment".into(),
            l_max: 1.0,
            seed: 0,
            iterations: 0,
            nodes: 0,
            joins: 0,
            node_checks: 0,
            edge_checks: 0,
            home_blocked: None,
            targets: vec![target(0, None), target(1, Some(path()))],
        };
        let out = dir.path().join("deep/traj");
        let files = write_trajectories(&report, &out).unwrap();
        assert_eq!(files, vec![out.join("task_1.csv"), out.join("task_1.json")]);
        let back: RosJointTrajectory =
            serde_json::from_str(&std::fs::read_to_string(&files[1]).unwrap()).unwrap();
        assert_eq!(back, Trajectory::from_path(&path()).to_ros());
        assert!(!out.join("task_0.csv").exists());
        // An earlier run's files of a task that now has no path go; other files stay.
        for name in ["task_0.csv", "task_0.json", "notes.txt"] {
            std::fs::write(out.join(name), "earlier").unwrap();
        }
        write_trajectories(&report, &out).unwrap();
        assert!(!out.join("task_0.csv").exists() && !out.join("task_0.json").exists());
        assert!(out.join("notes.txt").exists() && out.join("task_1.json").exists());
    }

    #[test]
    fn durations_split_into_seconds_and_nanoseconds() {
        let d = RosDuration::from_secs_f64(2.25);
        assert_eq!(
            d,
            RosDuration {
                secs: 2,
                nsecs: 250_000_000
            }
        );
        assert_eq!(
            RosDuration::from_secs_f64(-1.0),
            RosDuration { secs: 0, nsecs: 0 }
        );
    }
}
