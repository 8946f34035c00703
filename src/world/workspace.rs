//! The workspace: obstacles, task points and clearance (paper §II-B, Eq. 3–5).

use super::obstacle::Obstacle;
use super::task::TaskOrientation;
use crate::error::{Error, Result};
use crate::kinematics::Chain;
use crate::world::convert::to_parry_point;
use nalgebra::Point3;
use parry3d_f64::bounding_volume::{Aabb, BoundingVolume};
use parry3d_f64::partitioning::{Bvh, BvhBuildStrategy};

/// A place where the robot body comes within the clearance of an obstacle.
#[derive(Clone, Debug, PartialEq)]
pub struct Contact {
    /// Link index, from 1.
    pub link: usize,
    /// Obstacle index.
    pub obstacle: usize,
    /// Distance between the link capsule and the obstacle (0 when they overlap).
    pub distance: f64,
}

/// Obstacles `𝒪` and task points `𝒫` (paper Eq. 5), plus the clearance `ε` the robot must keep
/// (paper Eq. 15).
#[derive(Clone, Debug)]
pub struct Workspace {
    /// The obstacles.
    pub obstacles: Vec<Obstacle>,
    /// The task points the tool centre point must reach.
    pub tasks: Vec<Point3<f64>>,
    /// The orientation constraint of each task, in the order of `tasks` (all
    /// [`TaskOrientation::Free`] for point tasks).
    pub orientations: Vec<TaskOrientation>,
    /// Clearance `ε` (metres), at least 0.
    pub clearance: f64,
}

/// A bounding-volume hierarchy over the obstacles' bounding boxes (leaf `k`: obstacle `k`), so
/// that a check of every task or body against every obstacle costs what the nearby obstacles
/// cost, not all of them.
fn obstacle_bvh(obstacles: &[Obstacle]) -> Bvh {
    let boxes: Vec<Aabb> = obstacles
        .iter()
        .map(|o| o.shape().compute_aabb(o.pose()))
        .collect();
    Bvh::from_leaves(BvhBuildStrategy::Binned, &boxes)
}

/// The obstacles whose bounding boxes come within `margin` of the box of `points`, in index
/// order.
fn obstacles_near(bvh: &Bvh, points: &[Point3<f64>], margin: f64, out: &mut Vec<usize>) {
    let query = Aabb::from_points(points.iter().map(to_parry_point)).loosened(margin);
    out.clear();
    out.extend(bvh.intersect_aabb(&query).map(|k| k as usize));
    out.sort_unstable();
}

fn fmt_point(p: &Point3<f64>) -> String {
    format!("[{}, {}, {}]", p.x, p.y, p.z)
}

impl Workspace {
    /// A validated workspace.
    pub fn new(obstacles: Vec<Obstacle>, tasks: Vec<Point3<f64>>, clearance: f64) -> Result<Self> {
        let w = Workspace {
            orientations: vec![TaskOrientation::Free; tasks.len()],
            obstacles,
            tasks,
            clearance,
        };
        w.validate()?;
        Ok(w)
    }

    /// The same workspace with an orientation constraint per task (`orientations` has one
    /// entry per task).
    ///
    /// # Panics
    /// When the lengths differ.
    pub fn with_orientations(mut self, orientations: Vec<TaskOrientation>) -> Self {
        assert_eq!(
            orientations.len(),
            self.tasks.len(),
            "one orientation per task"
        );
        self.orientations = orientations;
        self
    }

    /// True when some task constrains the tool's orientation.
    pub fn has_orientations(&self) -> bool {
        self.orientations.iter().any(|o| !o.is_free())
    }

    /// Checks the clearance, that there is at least one task, that every task point is finite,
    /// and that every task point lies outside every obstacle (paper Eq. 4).
    pub fn validate(&self) -> Result<()> {
        if !(self.clearance.is_finite() && self.clearance >= 0.0) {
            return Err(Error::invalid(
                "clearance",
                self.clearance,
                "must be finite and not negative",
            ));
        }
        if self.tasks.is_empty() {
            return Err(Error::invalid(
                "task",
                "[]",
                "at least one task point is needed",
            ));
        }
        for (j, p) in self.tasks.iter().enumerate() {
            if !p.iter().all(|v| v.is_finite()) {
                return Err(Error::invalid(
                    format!("task[{j}].point"),
                    fmt_point(p),
                    "must be finite",
                ));
            }
        }
        let bvh = obstacle_bvh(&self.obstacles);
        let mut near = Vec::new();
        for (j, p) in self.tasks.iter().enumerate() {
            // Only the obstacles whose boxes hold the point can hold it.
            obstacles_near(&bvh, std::slice::from_ref(p), 0.0, &mut near);
            for &k in &near {
                let o = &self.obstacles[k];
                if o.contains_point(p) {
                    return Err(Error::TaskInsideObstacle {
                        task: j,
                        point: fmt_point(p),
                        obstacle: k,
                        name: o.name.clone(),
                    });
                }
            }
        }
        Ok(())
    }

    /// Every (link, obstacle) pair whose capsule (radius [`Chain::radius`] around each body
    /// segment) comes within the clearance of the obstacle at configuration `a`, with the
    /// smallest distance per pair.
    pub fn contacts(&self, chain: &Chain, a: &[f64]) -> Vec<Contact> {
        let mut frames = chain.frames();
        chain.fk(a, &mut frames);
        let mut out: Vec<Contact> = Vec::new();
        let bvh = obstacle_bvh(&self.obstacles);
        let mut near = Vec::new();
        for (s, seg) in frames.segments.iter().enumerate() {
            let link = chain.segment_link(s);
            // Obstacles farther than the clearance from the capsule's box cannot be within it.
            obstacles_near(&bvh, seg, chain.radius() + self.clearance, &mut near);
            for &k in &near {
                let o = &self.obstacles[k];
                let d = o.distance_to_capsule(&seg[0], &seg[1], chain.radius());
                if d <= self.clearance {
                    match out.iter_mut().find(|c| c.link == link && c.obstacle == k) {
                        Some(c) => c.distance = c.distance.min(d),
                        None => out.push(Contact {
                            link,
                            obstacle: k,
                            distance: d,
                        }),
                    }
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kinematics::{Axis, Dh, Link, Range};
    use nalgebra::IsometryMatrix3;

    #[test]
    fn task_inside_obstacle_names_both() {
        let o = Obstacle::sphere("drum", Point3::new(1.0, 0.0, 0.0), 0.3).unwrap();
        let e = Workspace::new(
            vec![o],
            vec![Point3::new(0.0, 0.0, 2.0), Point3::new(1.1, 0.0, 0.0)],
            0.0,
        )
        .unwrap_err();
        assert!(matches!(
            e,
            Error::TaskInsideObstacle {
                task: 1,
                obstacle: 0,
                ..
            }
        ));
        assert!(e.to_string().contains("drum"));
    }

    #[test]
    fn contacts_report_link_and_obstacle() {
        let mut r = [Range::ZERO; 6];
        r[Axis::Ry.index()] = Range::new(-1.0, 1.0);
        let link = Link::from_dh(
            &Dh {
                a: 1.0,
                ..Dh::default()
            },
            r,
        );
        let chain = Chain::new(IsometryMatrix3::identity(), &[link.clone(), link], 0.05, 2);
        let o = Obstacle::sphere("ball", Point3::new(1.5, 0.0, 0.1), 0.1).unwrap();
        let w = Workspace::new(vec![o], vec![Point3::new(0.0, 0.0, 1.0)], 0.0).unwrap();
        let c = w.contacts(&chain, chain.home());
        assert_eq!(c.len(), 1);
        assert_eq!((c[0].link, c[0].obstacle), (2, 0));
        // Joint 1, at the end of link 1, lifts link 2 clear of the ball.
        assert!(w.contacts(&chain, &[-0.5, 0.0]).is_empty());
        // Joint 2 sits at the tip: moving it does not move link 2.
        assert_eq!(w.contacts(&chain, &[0.0, -0.5]).len(), 1);
    }

    /// The checks culled by the obstacles' bounding boxes find what checking every pair finds:
    /// the first task inside an obstacle (by task, then obstacle), and every link–obstacle
    /// contact with its distance, in the same order; on random cells of spheres, boxes and
    /// capsules, rotated, with tasks and arms among them.
    #[test]
    fn culled_checks_are_those_of_every_pair() {
        use crate::world::ObstacleShape;
        use rand::{RngExt, SeedableRng};
        use rand_chacha::ChaCha8Rng;
        let mut rng = ChaCha8Rng::seed_from_u64(4);
        let mut r = [Range::ZERO; 6];
        r[Axis::Rz.index()] = Range::new(-3.0, 3.0);
        r[Axis::Ry.index()] = Range::new(-3.0, 3.0);
        let link = Link::from_dh(
            &Dh {
                a: 0.5,
                ..Dh::default()
            },
            r,
        );
        let chain = Chain::new(IsometryMatrix3::identity(), &vec![link; 4], 0.05, 2);
        let (mut inside, mut clear, mut contacts) = (0, 0, 0);
        for case in 0..200 {
            let count = rng.random_range(1..40);
            let mut coord = || rng.random_range(-1.5..1.5);
            let obstacles: Vec<Obstacle> = (0..count)
                .map(|k| {
                    let shape = match k % 3 {
                        0 => ObstacleShape::Sphere { radius: 0.25 },
                        1 => ObstacleShape::Cuboid {
                            size: [0.5, 0.3, 0.4],
                        },
                        _ => ObstacleShape::Capsule {
                            length: 0.4,
                            radius: 0.15,
                        },
                    };
                    let place = IsometryMatrix3::new(
                        nalgebra::Vector3::new(coord(), coord(), coord()),
                        nalgebra::Vector3::new(coord(), coord(), coord()),
                    );
                    Obstacle::new(format!("o{k}"), shape, place).unwrap()
                })
                .collect();
            let tasks: Vec<Point3<f64>> = (0..1 + count % 29)
                .map(|_| Point3::new(coord(), coord(), coord()))
                .collect();
            let clearance = if case % 2 == 0 { 0.0 } else { 0.05 };
            // Every pair, in order.
            let first = tasks.iter().enumerate().find_map(|(j, p)| {
                obstacles
                    .iter()
                    .position(|o| o.contains_point(p))
                    .map(|k| (j, k))
            });
            let w = Workspace {
                orientations: vec![TaskOrientation::Free; tasks.len()],
                obstacles: obstacles.clone(),
                tasks: tasks.clone(),
                clearance,
            };
            match (w.validate(), first) {
                (Ok(()), None) => clear += 1,
                (Err(Error::TaskInsideObstacle { task, obstacle, .. }), Some(want)) => {
                    assert_eq!((task, obstacle), want, "case {case}");
                    inside += 1;
                }
                (got, want) => panic!("case {case}: {got:?} against {want:?}"),
            }
            let a: Vec<f64> = (0..chain.dof())
                .map(|_| rng.random_range(-3.0..3.0))
                .collect();
            let mut frames = chain.frames();
            chain.fk(&a, &mut frames);
            let mut want: Vec<Contact> = Vec::new();
            for (s, seg) in frames.segments.iter().enumerate() {
                for (k, o) in obstacles.iter().enumerate() {
                    let d = o.distance_to_capsule(&seg[0], &seg[1], chain.radius());
                    if d <= clearance {
                        let link = chain.segment_link(s);
                        match want.iter_mut().find(|c| c.link == link && c.obstacle == k) {
                            Some(c) => c.distance = c.distance.min(d),
                            None => want.push(Contact {
                                link,
                                obstacle: k,
                                distance: d,
                            }),
                        }
                    }
                }
            }
            contacts += want.len();
            assert_eq!(w.contacts(&chain, &a), want, "case {case}");
        }
        assert!(
            inside > 20 && clear > 20 && contacts > 50,
            "{inside} {clear} {contacts}"
        );
    }
}
