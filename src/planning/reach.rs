//! Reachability of a design (paper Eq. 11–12): the share of task points an RRT from home
//! reaches without collision, with a replayable path for each.

use super::rrt::Rrt;
use super::PlannerConfig;
use crate::collision::{make_checker, CollisionScene, RobotBody, Scratch};
use crate::kinematics::Chain;
use crate::world::TaskOrientation;
use nalgebra::Point3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

/// A joint-space path, keyed by joint names so it replays on the exported URDF.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PathReport {
    /// Joint names (`j{link}_{axis}`), one per free axis.
    pub joint_names: Vec<String>,
    /// Configurations from home to the task, one value per joint.
    pub points: Vec<Vec<f64>>,
}

/// The outcome for one task point.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct TargetReport {
    /// Index of the task in the scenario.
    pub index: usize,
    /// The task point.
    pub point: [f64; 3],
    /// True when a node within the goal tolerance was reached.
    pub reached: bool,
    /// End effector (the tool centre point) of the reaching node, or of the tree's closest
    /// node when unreached.
    pub end_effector: [f64; 3],
    /// Distance between `end_effector` and `point`.
    pub error: f64,
    /// The same distance under the name the oriented reports use (metres).
    #[serde(default)]
    pub position_error: f64,
    /// For a task with a full orientation: the rotation angle (radians) between the TCP frame
    /// of that node and the task's orientation.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub orientation_error: Option<f64>,
    /// For a task with an approach cone: the angle (radians) between the TCP's z axis at that
    /// node and the approach direction.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub approach_error: Option<f64>,
    /// The orientation or approach tolerance (radians) of the task, when it has one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub orientation_tolerance: Option<f64>,
    /// The TCP rotation of that node, row by row (a task with an orientation or approach).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tool_rotation: Option<[[f64; 3]; 3]>,
    /// Why the task is unreached (absent when reached).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
    /// The path from home, when reached (and kept: see `path_omitted`).
    pub path: Option<PathReport>,
    /// Why a reached task carries no path: the report's paths together would have exceeded
    /// [`crate::limits::MAX_REPORT_PATH_VALUES`] values (points times joints, and the joint
    /// names: [`path_cost`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub path_omitted: Option<String>,
}

/// Reachability of one design, with per-task outcomes and the planner's work counters.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ReachReport {
    /// `R = |reached| / |tasks|` (paper Eq. 12).
    pub reachability: f64,
    /// Edge checker used.
    pub checker: String,
    /// Step bound `L_max` used.
    pub l_max: f64,
    /// Seed of the planner's random stream.
    pub seed: u64,
    /// RRT iterations.
    pub iterations: usize,
    /// Tree nodes.
    pub nodes: usize,
    /// Backward trees (grown from collision-free IK postures of tasks) joined to the tree from
    /// home; each reached its task through the join.
    #[serde(default)]
    pub joins: usize,
    /// Node checks made.
    pub node_checks: u64,
    /// Edge checks made.
    pub edge_checks: u64,
    /// Why nothing was reached when the home pose collides.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub home_blocked: Option<String>,
    /// One entry per task, in scenario order.
    pub targets: Vec<TargetReport>,
    /// The planner's tree, when asked for ([`reachability_with_tree`], `reach --tree`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tree: Option<TreeReport>,
}

/// The planner's tree as its nodes' end effectors and parents, for drawing the search.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TreeReport {
    /// End effector of each node, in the order the nodes were added (grafted backward trees
    /// after the nodes of the tree from home).
    pub end_effectors: Vec<[f64; 3]>,
    /// Parent of each node (the root, node 0, is its own parent).
    pub parents: Vec<u32>,
}

impl ReachReport {
    /// Number of reached tasks.
    pub fn reached(&self) -> usize {
        self.targets.iter().filter(|t| t.reached).count()
    }

    /// The report as pretty-printed JSON.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).expect("a report always serialises")
    }

    /// The report as JSON with the random `stream` it was planned with (`"stream"`), as
    /// `kinsynth reach --json` and an optimiser's `reach.json` write it.
    pub fn to_json_value(&self, stream: u64) -> serde_json::Value {
        let mut v = serde_json::to_value(self).expect("a report always serialises");
        v["stream"] = stream.into();
        v
    }
}

/// What a path of `points` configurations over the joints `names` counts against
/// [`crate::limits::MAX_REPORT_PATH_VALUES`]: its values (points times joints, at least one
/// joint), and its joint names at one value per 8 bytes (each path carries them).
pub fn path_cost(points: usize, names: &[String]) -> usize {
    let text: usize = names.iter().map(|n| n.len().saturating_add(4)).sum();
    points
        .saturating_mul(names.len().max(1))
        .saturating_add(text.div_ceil(8))
}

/// Takes a path of `points` configurations over the joints `names` from what is left of a
/// report's `budget`, if it fits ([`path_cost`]).
fn take_path(budget: &mut usize, points: usize, names: &[String]) -> bool {
    let cost = path_cost(points, names);
    let fits = cost <= *budget;
    if fits {
        *budget -= cost;
    }
    fits
}

/// Why a reached task's path of `points` configurations is left out of its report.
fn path_omitted(points: usize) -> String {
    format!(
        "its path of {points} points would take the report's paths beyond the limit of {} values (points times joints, and the joint names)",
        crate::limits::MAX_REPORT_PATH_VALUES
    )
}

/// Gives every kept path of `report` the joint names `names` (an imported robot's URDF joint
/// names, in actuation-vector order, so the paths replay on that URDF), keeping the report's
/// paths within [`crate::limits::MAX_REPORT_PATH_VALUES`] with those names ([`path_cost`]):
/// in task order, a path that no longer fits is left out and its task says why.
pub fn rename_joints(report: &mut ReachReport, names: &[String]) {
    let mut budget = crate::limits::MAX_REPORT_PATH_VALUES;
    for t in &mut report.targets {
        let Some(p) = &mut t.path else { continue };
        if take_path(&mut budget, p.points.len(), names) {
            p.joint_names.clear();
            p.joint_names.extend_from_slice(names);
        } else {
            t.path_omitted = Some(path_omitted(p.points.len()));
            t.path = None;
        }
    }
}

/// The random stream of a reachability evaluation: ChaCha8 seeded with `seed`, on stream
/// `stream` (e.g. an individual's index in an optimiser), so results never depend on which
/// thread runs them.
pub fn planner_rng(seed: u64, stream: u64) -> ChaCha8Rng {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(stream);
    rng
}

/// Says why the home pose is blocked: the body deepest in an obstacle (or nearest to one,
/// within the clearance), with how many bodies are within the clearance; or else the first
/// checked self pair in contact, naming the links.
fn home_collision(scene: &CollisionScene, chain: &Chain, body: &RobotBody) -> String {
    if let Some((a, b)) = body.acm().home_fold() {
        return format!(
            "home pose self-collides: the bodies of link {a} and link {b} cross each other"
        );
    }
    let mut frames = chain.frames();
    let mut placed = crate::collision::body::Placed::default();
    chain.fk(chain.home(), &mut frames);
    body.place(&frames, &mut placed);
    // (distance, body, obstacle) of the deepest contact, and the bodies within the clearance.
    let mut deepest: Option<(f64, usize, usize)> = None;
    let mut bodies = 0;
    let mut near = Vec::new();
    for b in 0..body.len() {
        let mut hit = false;
        // Only the obstacles near the body's bounding ball can be within its clearance (the
        // scene's broad phase), in index order.
        let (center, radius) = body.ball(&frames, &placed, b);
        scene.near(&center, radius, scene.clearance() + 1e-9, &mut near);
        near.sort_unstable();
        for k in near.iter().map(|&k| k as usize) {
            if body.obstacle_distance(scene, &frames, &placed, b, k) > scene.clearance() {
                continue;
            }
            hit = true;
            let d = body.obstacle_signed_distance(scene, &frames, &placed, b, k);
            if deepest.is_none_or(|(best, _, _)| d < best) {
                deepest = Some((d, b, k));
            }
        }
        bodies += usize::from(hit);
    }
    if let Some((d, b, k)) = deepest {
        let what = if d < 0.0 {
            format!("is {:.4} m deep in", -d)
        } else if d == 0.0 {
            "touches".to_string()
        } else {
            format!("is {d:.4} m from")
        };
        let others = match bodies {
            1 => String::new(),
            2 => " (1 more body is within the clearance)".to_string(),
            n => format!(" ({} more bodies are within the clearance)", n - 1),
        };
        return format!(
            "home pose collides: link {} ({}) {what} obstacle[{k}] ({}), clearance {} m{others}",
            body.link(b),
            body.frame(b),
            scene.obstacles()[k].name,
            scene.clearance()
        );
    }
    if let Some((p, q, _)) = body.self_contact(&frames, &placed) {
        return format!(
            "home pose self-collides: link {} ({}) touches link {} ({})",
            body.link(p),
            body.frame(p),
            body.link(q),
            body.frame(q)
        );
    }
    "home pose collides (a point collider is within the clearance of an obstacle)".into()
}

/// Evaluates the reachability of `chain` over `tasks` in `scene` with the planner settings
/// `config` (its checker, body model, `l_max`, iterations, …) and the random stream
/// `(seed, stream)`. The robot body is the chain's capsules with the self-collision settings of
/// `config`. A design whose home pose collides or self-collides has `R = 0` and says why.
pub fn reachability(
    chain: &Chain,
    scene: &Arc<CollisionScene>,
    tasks: &[Point3<f64>],
    config: &PlannerConfig,
    seed: u64,
    stream: u64,
) -> ReachReport {
    reachability_tasks(chain, None, scene, tasks, &[], config, seed, stream)
}

/// As [`reachability`], for a given robot body of `chain` (for example an imported arm's
/// collision meshes).
pub fn reachability_of(
    chain: &Chain,
    body: Arc<RobotBody>,
    scene: &Arc<CollisionScene>,
    tasks: &[Point3<f64>],
    config: &PlannerConfig,
    seed: u64,
    stream: u64,
) -> ReachReport {
    reachability_tasks(chain, Some(body), scene, tasks, &[], config, seed, stream)
}

/// As [`reachability`], for tasks with orientation constraints (`orientations` one per task, or
/// empty for point tasks; see [`Rrt::with_orientations`]) and an optional robot body (default:
/// the chain's capsules). Each task's report gives its position error and, for an oriented
/// task, its orientation or approach error at the reaching node (or at the tree's node nearest
/// to the point when unreached), and for an unreached task the reason.
#[allow(clippy::too_many_arguments)]
pub fn reachability_tasks(
    chain: &Chain,
    body: Option<Arc<RobotBody>>,
    scene: &Arc<CollisionScene>,
    tasks: &[Point3<f64>],
    orientations: &[TaskOrientation],
    config: &PlannerConfig,
    seed: u64,
    stream: u64,
) -> ReachReport {
    let run = (tasks, orientations);
    reachability_until(chain, body, scene, run, config, (seed, stream), None)
        .expect("a run without an interrupt flag ends whole")
}

/// As [`reachability_tasks`] (the tasks with their orientations, the seed with the stream),
/// stopped before the planner's next iteration once `interrupt` is raised (a user's stop
/// signal): `None` then, since the report would not be the one of a whole run.
pub fn reachability_until(
    chain: &Chain,
    body: Option<Arc<RobotBody>>,
    scene: &Arc<CollisionScene>,
    tasks: (&[Point3<f64>], &[TaskOrientation]),
    config: &PlannerConfig,
    (seed, stream): (u64, u64),
    interrupt: Option<&AtomicBool>,
) -> Option<ReachReport> {
    plan(
        chain,
        body,
        scene,
        tasks,
        config,
        (seed, stream),
        false,
        interrupt,
    )
}

/// As [`reachability_tasks`], with the planner's tree in [`ReachReport::tree`]. Everything else
/// in the report is the same as [`reachability_tasks`]'s for the same arguments.
#[allow(clippy::too_many_arguments)]
pub fn reachability_with_tree(
    chain: &Chain,
    body: Option<Arc<RobotBody>>,
    scene: &Arc<CollisionScene>,
    tasks: &[Point3<f64>],
    orientations: &[TaskOrientation],
    config: &PlannerConfig,
    seed: u64,
    stream: u64,
) -> ReachReport {
    plan(
        chain,
        body,
        scene,
        (tasks, orientations),
        config,
        (seed, stream),
        true,
        None,
    )
    .expect("a run without an interrupt flag ends whole")
}

#[allow(clippy::too_many_arguments)]
fn plan(
    chain: &Chain,
    body: Option<Arc<RobotBody>>,
    scene: &Arc<CollisionScene>,
    (tasks, orientations): (&[Point3<f64>], &[TaskOrientation]),
    config: &PlannerConfig,
    (seed, stream): (u64, u64),
    keep_tree: bool,
    interrupt: Option<&AtomicBool>,
) -> Option<ReachReport> {
    let body = body.unwrap_or_else(|| Arc::new(RobotBody::capsules(chain, &config.self_collision)));
    let checker = make_checker(config.checker, scene.clone(), config.body);
    let mut scratch = Scratch::with_body(chain, body.clone());
    let mut rng = planner_rng(seed, stream);
    let folded = body.acm().home_fold().is_some();
    let growth = if folded {
        super::rrt::Growth::blocked(chain, tasks.len())
    } else {
        let rrt = Rrt::new(chain, checker.as_ref(), config, tasks).with_orientations(orientations);
        match interrupt {
            Some(flag) => rrt.with_interrupt(flag),
            None => rrt,
        }
        .grow(&mut rng, &mut scratch)
    };
    if growth.interrupted {
        return None;
    }
    let names = chain.joint_names();
    let tree = &growth.tree;
    let mut home_frames = chain.frames();
    chain.fk(chain.home(), &mut home_frames);
    let origin = Point3::from(chain.base().translation.vector);
    let bound = chain.reach_bound();
    // Paths are kept in task order while they together stay within the limit; a reached
    // task whose path would exceed it keeps its outcome and says why it has none.
    let lengths = tree.path_lengths();
    let mut budget = crate::limits::MAX_REPORT_PATH_VALUES;
    let kept: Vec<bool> = growth
        .reached
        .iter()
        .map(|n| n.is_some_and(|n| take_path(&mut budget, lengths[n as usize] as usize, &names)))
        .collect();
    let targets: Vec<TargetReport> = tasks
        .iter()
        .enumerate()
        .map(|(index, p)| {
            let node = growth.reached[index]
                .or_else(|| (!tree.is_empty()).then(|| tree.nearest_end_effector(p)));
            let ee = node.map_or_else(|| home_frames.end_effector(), |n| tree.end_effector(n));
            let rot = node.map_or(*home_frames.tcp_rotation(), |n| *tree.tcp_rotation(n));
            let reached = growth.reached[index].is_some();
            let o = orientations.get(index).copied().unwrap_or_default();
            let error = (ee - p).norm();
            let angle = (!o.is_free()).then(|| o.error(&rot));
            // A run stopped by the checker's work limit says so where it gives its iterations.
            let spent = if growth.work_limited {
                format!(
                    "{} iterations, stopped at the ccd checker's work limit of {} shape casts per run",
                    growth.iterations,
                    crate::limits::MAX_CCD_CASTS
                )
            } else if growth.node_limited {
                format!(
                    "{} iterations, stopped at the planner's limit of {} tree nodes per run for {} axes",
                    growth.iterations,
                    crate::limits::node_cap(chain.dof()),
                    chain.dof()
                )
            } else if growth.tests_limited {
                format!(
                    "{} iterations, stopped at the checker's work limit of {} body tests per run ({} per check: each body and checked self pair)",
                    growth.iterations,
                    crate::limits::MAX_BODY_TESTS,
                    body.len() + body.self_pairs().len()
                )
            } else if growth.fk_limited {
                format!(
                    "{} iterations, stopped at the checker's work limit of {} kinematics evaluations per run",
                    growth.iterations,
                    crate::limits::MAX_CHECK_FK
                )
            } else {
                format!("{} iterations", growth.iterations)
            };
            let reason = (!reached).then(|| {
                let far = (p - origin).norm();
                if growth.home_blocked {
                    "the home pose is blocked".to_string()
                } else if far > bound + config.goal_tolerance {
                    format!(
                        "the point is {far:.4} m from the base, beyond the design's reach bound of {bound:.4} m plus the goal tolerance"
                    )
                } else if let Some(why) = super::feasible::impossible_orientation(chain, &o) {
                    why
                } else if o.is_free() {
                    format!(
                        "no collision-free path brought the tool within {} m of the point in {spent} (closest {error:.4} m)",
                        config.goal_tolerance
                    )
                } else {
                    format!(
                        "no collision-free path brought the tool within {} m of the point and {:.1}° of the task's {} in {spent} (closest node: {error:.4} m, {:.1}°)",
                        config.goal_tolerance,
                        o.tolerance().to_degrees(),
                        match o {
                            TaskOrientation::Approach { .. } => "approach direction",
                            _ => "orientation",
                        },
                        angle.unwrap_or(0.0).to_degrees()
                    )
                }
            });
            TargetReport {
                index,
                point: [p.x, p.y, p.z],
                reached,
                end_effector: [ee.x, ee.y, ee.z],
                error,
                position_error: error,
                orientation_error: angle.filter(|_| matches!(o, TaskOrientation::Pose { .. })),
                approach_error: angle
                    .filter(|_| matches!(o, TaskOrientation::Approach { .. })),
                orientation_tolerance: (!o.is_free()).then(|| o.tolerance()),
                tool_rotation: (!o.is_free()).then(|| {
                    [0, 1, 2].map(|i| [rot[(i, 0)], rot[(i, 1)], rot[(i, 2)]])
                }),
                reason,
                path: growth.reached[index]
                    .filter(|_| kept[index])
                    .map(|n| PathReport {
                        joint_names: names.clone(),
                        points: tree.path_to(n),
                    }),
                path_omitted: (reached && !kept[index]).then(|| {
                    path_omitted(growth.reached[index].map_or(0, |n| lengths[n as usize] as usize))
                }),
            }
        })
        .collect();
    let reached = targets.iter().filter(|t| t.reached).count();
    Some(ReachReport {
        reachability: if tasks.is_empty() {
            0.0
        } else {
            reached as f64 / tasks.len() as f64
        },
        checker: checker.name().to_string(),
        l_max: config.l_max,
        seed,
        iterations: growth.iterations,
        nodes: tree.len(),
        joins: growth.joins,
        node_checks: scratch.stats.nodes,
        edge_checks: scratch.stats.edges,
        home_blocked: growth
            .home_blocked
            .then(|| home_collision(scene, chain, &body)),
        targets,
        tree: keep_tree.then(|| TreeReport {
            end_effectors: (0..tree.len() as u32)
                .map(|n| {
                    let e = tree.end_effector(n);
                    [e.x, e.y, e.z]
                })
                .collect(),
            parents: (0..tree.len() as u32).map(|n| tree.parent(n)).collect(),
        }),
    })
}
