//! The workspace: obstacles, task points and clearance (paper §II-B, Eq. 3–5).

use super::obstacle::Obstacle;
use super::task::TaskOrientation;
use crate::error::{Error, Result};
use crate::kinematics::Chain;
use nalgebra::Point3;

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
            for (k, o) in self.obstacles.iter().enumerate() {
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
        for (s, seg) in frames.segments.iter().enumerate() {
            let link = chain.segment_link(s);
            for (k, o) in self.obstacles.iter().enumerate() {
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
}
