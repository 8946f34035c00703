//! Reachability of a design (paper Eq. 11–12): the share of task points an RRT from home
//! reaches without collision, with a replayable path for each.

use super::rrt::Rrt;
use super::PlannerConfig;
use crate::collision::{make_checker, CollisionScene, RobotBody, Scratch};
use crate::kinematics::Chain;
use nalgebra::Point3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
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
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TargetReport {
    /// Index of the task in the scenario.
    pub index: usize,
    /// The task point.
    pub point: [f64; 3],
    /// True when a node within the goal tolerance was reached.
    pub reached: bool,
    /// End effector of the reaching node, or of the tree's closest node when unreached.
    pub end_effector: [f64; 3],
    /// Distance between `end_effector` and `point`.
    pub error: f64,
    /// The path from home, when reached.
    pub path: Option<PathReport>,
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
}

/// The random stream of a reachability evaluation: ChaCha8 seeded with `seed`, on stream
/// `stream` (e.g. an individual's index in an optimiser), so results never depend on which
/// thread runs them.
pub fn planner_rng(seed: u64, stream: u64) -> ChaCha8Rng {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(stream);
    rng
}

/// Says why the home pose is blocked: the first body within the clearance of an obstacle, or
/// the first checked self pair in contact, naming the links.
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
    for b in 0..body.len() {
        for (k, o) in scene.obstacles().iter().enumerate() {
            let d = body.obstacle_distance(scene, &frames, &placed, b, k);
            if d <= scene.clearance() {
                return format!(
                    "home pose collides: link {} ({}) is {:.4} m from obstacle[{k}] ({}), clearance {} m",
                    body.link(b),
                    body.frame(b),
                    d.max(0.0),
                    o.name,
                    scene.clearance()
                );
            }
        }
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
    let body = Arc::new(RobotBody::new(chain, Vec::new(), &config.self_collision));
    reachability_of(chain, body, scene, tasks, config, seed, stream)
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
    plan(chain, body, scene, tasks, config, (seed, stream), false)
}

/// As [`reachability_of`], with the planner's tree in [`ReachReport::tree`]. Everything else
/// in the report is the same as [`reachability_of`]'s for the same arguments.
pub fn reachability_with_tree(
    chain: &Chain,
    body: Arc<RobotBody>,
    scene: &Arc<CollisionScene>,
    tasks: &[Point3<f64>],
    config: &PlannerConfig,
    seed: u64,
    stream: u64,
) -> ReachReport {
    plan(chain, body, scene, tasks, config, (seed, stream), true)
}

fn plan(
    chain: &Chain,
    body: Arc<RobotBody>,
    scene: &Arc<CollisionScene>,
    tasks: &[Point3<f64>],
    config: &PlannerConfig,
    (seed, stream): (u64, u64),
    keep_tree: bool,
) -> ReachReport {
    let checker = make_checker(config.checker, scene.clone(), config.body);
    let mut scratch = Scratch::with_body(chain, body.clone());
    let mut rng = planner_rng(seed, stream);
    let folded = body.acm().home_fold().is_some();
    let growth = if folded {
        super::rrt::Growth::blocked(chain, tasks.len())
    } else {
        Rrt::new(chain, checker.as_ref(), config, tasks).grow(&mut rng, &mut scratch)
    };
    let names = chain.joint_names();
    let tree = &growth.tree;
    let targets: Vec<TargetReport> = tasks
        .iter()
        .enumerate()
        .map(|(index, p)| {
            let node = growth.reached[index]
                .or_else(|| (!tree.is_empty()).then(|| tree.nearest_end_effector(p)));
            let ee = node.map_or_else(
                || chain.end_effector(chain.home()),
                |n| tree.end_effector(n),
            );
            let reached = growth.reached[index].is_some();
            TargetReport {
                index,
                point: [p.x, p.y, p.z],
                reached,
                end_effector: [ee.x, ee.y, ee.z],
                error: (ee - p).norm(),
                path: growth.reached[index].map(|n| PathReport {
                    joint_names: names.clone(),
                    points: tree.path_to(n),
                }),
            }
        })
        .collect();
    let reached = targets.iter().filter(|t| t.reached).count();
    ReachReport {
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
    }
}
