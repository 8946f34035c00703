//! The design space (paper Eq. 22, 24–25): which design variables are free, their bounds, and
//! the flat vector the optimisers work on.

use super::design::{Design, LinkDesign};
use crate::error::{Error, Result};
use crate::kinematics::{Axis, Range};

/// One kind of design variable of a link.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Param {
    /// DH θ.
    Theta,
    /// DH d.
    D,
    /// DH a (link length).
    A,
    /// DH α.
    Alpha,
    /// Lower limit of an axis range (paper Eq. 20).
    Min(Axis),
    /// Upper limit of an axis range (paper Eq. 21).
    Max(Axis),
}

impl Param {
    /// Short name: `theta`, `d`, `a`, `alpha`, `ry.min`, `tx.max`, …
    pub fn name(&self) -> String {
        match self {
            Param::Theta => "theta".into(),
            Param::D => "d".into(),
            Param::A => "a".into(),
            Param::Alpha => "alpha".into(),
            Param::Min(a) => format!("{a}.min"),
            Param::Max(a) => format!("{a}.max"),
        }
    }

    fn get(&self, l: &LinkDesign) -> f64 {
        match *self {
            Param::Theta => l.theta,
            Param::D => l.d,
            Param::A => l.a,
            Param::Alpha => l.alpha,
            Param::Min(a) => l.axes.get(a).min,
            Param::Max(a) => l.axes.get(a).max,
        }
    }

    fn set(&self, l: &mut LinkDesign, v: f64) {
        match *self {
            Param::Theta => l.theta = v,
            Param::D => l.d = v,
            Param::A => l.a = v,
            Param::Alpha => l.alpha = v,
            Param::Min(a) => l.axes.get_mut(a).min = v,
            Param::Max(a) => l.axes.get_mut(a).max = v,
        }
    }
}

/// A free design variable: a parameter of one link with its bounds (paper Eq. 24–25).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Variable {
    /// Link index, from 1.
    pub link: usize,
    /// Which parameter.
    pub param: Param,
    /// Lower bound.
    pub lower: f64,
    /// Upper bound.
    pub upper: f64,
}

impl Variable {
    /// Name like `link3.a` or `link2.ry.min`.
    pub fn name(&self) -> String {
        format!("link{}.{}", self.link, self.param.name())
    }
}

/// The design space: a template design that holds every fixed value, the list of free
/// variables, and the snap threshold for topology synthesis.
///
/// [`DesignSpace::decode`] maps a flat vector `x` (one entry per free variable, in order) to a
/// [`Design`]. Values within `snap` of zero become exactly zero, so an optimiser can remove a
/// link (`a = d = 0`) or a joint (`min = max`), as the paper's objective rewards (Eq. 28–29).
#[derive(Clone, Debug, PartialEq)]
pub struct DesignSpace {
    template: Design,
    variables: Vec<Variable>,
    snap: f64,
}

impl DesignSpace {
    /// A design space from a template, its free variables and the snap threshold. Bounds must be
    /// finite with `lower ≤ upper`, links must exist, and a parameter may be free only once.
    pub fn new(template: Design, variables: Vec<Variable>, snap: f64) -> Result<Self> {
        if !(snap.is_finite() && snap >= 0.0) {
            return Err(Error::invalid(
                "snap",
                snap,
                "must be finite and not negative",
            ));
        }
        for (k, v) in variables.iter().enumerate() {
            let field = v.name();
            if v.link == 0 || v.link > template.links.len() {
                return Err(Error::invalid(field, v.link, "no such link"));
            }
            if !(v.lower.is_finite() && v.upper.is_finite()) {
                return Err(Error::invalid(
                    field,
                    format!("[{}, {}]", v.lower, v.upper),
                    "bounds must be finite",
                ));
            }
            if v.lower > v.upper {
                return Err(Error::invalid(
                    field,
                    format!("[{}, {}]", v.lower, v.upper),
                    "lower bound exceeds upper bound",
                ));
            }
            if variables[..k]
                .iter()
                .any(|w| w.link == v.link && w.param == v.param)
            {
                return Err(Error::invalid(
                    field,
                    "twice",
                    "a variable may be free once",
                ));
            }
        }
        Ok(DesignSpace {
            template,
            variables,
            snap,
        })
    }

    /// Number of free variables.
    pub fn dim(&self) -> usize {
        self.variables.len()
    }

    /// The free variables, in vector order.
    pub fn variables(&self) -> &[Variable] {
        &self.variables
    }

    /// The template: fixed values, and the starting values of the free ones.
    pub fn template(&self) -> &Design {
        &self.template
    }

    /// The snap threshold.
    pub fn snap(&self) -> f64 {
        self.snap
    }

    /// Lower bounds, in vector order.
    pub fn lower(&self) -> Vec<f64> {
        self.variables.iter().map(|v| v.lower).collect()
    }

    /// Upper bounds, in vector order.
    pub fn upper(&self) -> Vec<f64> {
        self.variables.iter().map(|v| v.upper).collect()
    }

    /// The free variables of `design` as a flat vector (no clamping or snapping).
    pub fn encode(&self, design: &Design) -> Vec<f64> {
        self.variables
            .iter()
            .map(|v| v.param.get(&design.links[v.link - 1]))
            .collect()
    }

    /// The design for a flat vector `x`:
    /// 1. each value is clamped into its bounds (a NaN becomes the lower bound);
    /// 2. values with `|v| < snap` become 0;
    /// 3. per axis, `min > max` is repaired by swapping the two (the order constraint of paper
    ///    Eq. 25 becomes a symmetry instead of a penalty);
    /// 4. a range narrower than `snap` collapses to its midpoint (itself snapped to 0), so the
    ///    axis stops being a joint.
    ///
    /// # Panics
    /// When `x.len() != self.dim()`; [`DesignSpace::try_decode`] returns an error instead.
    pub fn decode(&self, x: &[f64]) -> Design {
        assert_eq!(x.len(), self.variables.len(), "design vector length");
        self.decode_unchecked(x)
    }

    /// [`DesignSpace::decode`] for a vector from outside (a file): a vector whose length is
    /// not [`DesignSpace::dim`] is an error naming both lengths.
    pub fn try_decode(&self, x: &[f64]) -> Result<Design> {
        if x.len() != self.variables.len() {
            return Err(Error::invalid(
                "design vector",
                format!("{} values", x.len()),
                format!(
                    "the design space has {} free variables",
                    self.variables.len()
                ),
            ));
        }
        Ok(self.decode_unchecked(x))
    }

    fn decode_unchecked(&self, x: &[f64]) -> Design {
        let mut d = self.template.clone();
        let snap = |v: f64| if v.abs() < self.snap { 0.0 } else { v };
        for (v, &val) in self.variables.iter().zip(x) {
            let val = if val.is_nan() {
                v.lower
            } else {
                val.clamp(v.lower, v.upper)
            };
            v.param.set(&mut d.links[v.link - 1], snap(val));
        }
        for l in &mut d.links {
            for r in &mut l.axes.0 {
                if r.min > r.max {
                    *r = Range::new(r.max, r.min);
                }
                if r.width() < self.snap {
                    let mid = snap(0.5 * (r.min + r.max));
                    *r = Range::new(mid, mid);
                }
            }
        }
        d
    }

    /// The largest design with one link removed, for each link that the space can remove
    /// (its free lengths `a` and `d` admit zero and at least one of them is free): the
    /// largest design's neighbours one link shorter (paper Eq. 28), in link order.
    pub fn largest_shortened(&self) -> Vec<Design> {
        let x = self.encode(&self.largest());
        let links = self.variables.iter().map(|v| v.link).max().unwrap_or(0);
        (1..=links)
            .filter_map(|link| {
                let lengths: Vec<usize> = (0..self.variables.len())
                    .filter(|&i| {
                        let v = &self.variables[i];
                        v.link == link && matches!(v.param, Param::A | Param::D)
                    })
                    .collect();
                let removable = !lengths.is_empty()
                    && lengths.iter().all(|&i| {
                        let v = &self.variables[i];
                        v.lower <= 0.0 && 0.0 <= v.upper
                    })
                    && lengths.iter().any(|&i| x[i] != 0.0);
                removable.then(|| {
                    let mut y = x.clone();
                    for &i in &lengths {
                        y[i] = 0.0;
                    }
                    self.decode(&y)
                })
            })
            .collect()
    }

    /// The largest design of the space, used to check the workspace: lengths and offsets at
    /// the bound of larger magnitude, every range at its widest (lower bound of its min, upper
    /// bound of its max), and the angles θ, α at the middle of their bounds.
    pub fn largest(&self) -> Design {
        let x: Vec<f64> = self
            .variables
            .iter()
            .map(|v| match v.param {
                Param::A | Param::D => {
                    if v.upper.abs() >= v.lower.abs() {
                        v.upper
                    } else {
                        v.lower
                    }
                }
                Param::Min(_) => v.lower,
                Param::Max(_) => v.upper,
                Param::Theta | Param::Alpha => 0.5 * (v.lower + v.upper),
            })
            .collect();
        self.decode(&x)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kinematics::Placement;

    fn space(snap: f64) -> DesignSpace {
        let template = Design {
            base: Placement::default(),
            link_radius: 0.02,
            colliders_per_link: 2,
            links: vec![LinkDesign::default(); 2],
            tool: None,
        };
        let vars = vec![
            Variable {
                link: 1,
                param: Param::A,
                lower: 0.0,
                upper: 0.5,
            },
            Variable {
                link: 2,
                param: Param::Min(Axis::Ry),
                lower: -3.0,
                upper: 0.0,
            },
            Variable {
                link: 2,
                param: Param::Max(Axis::Ry),
                lower: 0.0,
                upper: 3.0,
            },
        ];
        DesignSpace::new(template, vars, snap).unwrap()
    }

    #[test]
    fn decode_encode_round_trip_inside_bounds() {
        let s = space(1e-3);
        let x = vec![0.3, -1.0, 2.0];
        let d = s.decode(&x);
        assert_eq!(s.encode(&d), x);
        assert_eq!(d.links[1].axes.get(Axis::Ry), Range::new(-1.0, 2.0));
    }

    #[test]
    fn decode_snaps_clamps_and_removes_joints() {
        let s = space(1e-2);
        let d = s.decode(&[0.004, -0.005, 0.009]);
        assert_eq!(d.links[0].a, 0.0, "short link removed");
        assert_eq!(d.links[1].axes.get(Axis::Ry), Range::ZERO, "joint removed");
        assert_eq!(d.links_kept(), 0);
        assert_eq!(d.joints_kept(), 0);
        let d = s.decode(&[7.0, f64::NAN, 1.0]);
        assert_eq!(d.links[0].a, 0.5, "clamped to the upper bound");
        assert_eq!(d.links[1].axes.get(Axis::Ry), Range::new(-3.0, 1.0));
    }

    #[test]
    fn swapped_limits_are_repaired() {
        let template = Design {
            base: Placement::default(),
            link_radius: 0.0,
            colliders_per_link: 0,
            links: vec![LinkDesign::default()],
            tool: None,
        };
        let vars = vec![
            Variable {
                link: 1,
                param: Param::Min(Axis::Tx),
                lower: -1.0,
                upper: 1.0,
            },
            Variable {
                link: 1,
                param: Param::Max(Axis::Tx),
                lower: -1.0,
                upper: 1.0,
            },
        ];
        let s = DesignSpace::new(template, vars, 1e-3).unwrap();
        let d = s.decode(&[0.8, -0.2]);
        assert_eq!(d.links[0].axes.get(Axis::Tx), Range::new(-0.2, 0.8));
        let d = s.decode(&[0.5, 0.5004]);
        assert_eq!(d.links[0].axes.get(Axis::Tx), Range::new(0.5002, 0.5002));
    }

    #[test]
    fn try_decode_refuses_a_vector_of_the_wrong_length() {
        let s = space(1e-3);
        let e = s.try_decode(&[0.1, 0.2]).unwrap_err().to_string();
        assert!(
            e.contains("2 values") && e.contains("3 free variables"),
            "{e}"
        );
        assert_eq!(
            s.try_decode(&[0.3, -1.0, 2.0]).unwrap(),
            s.decode(&[0.3, -1.0, 2.0])
        );
    }

    #[test]
    fn largest_takes_the_widest_ranges_and_longest_links() {
        let d = space(1e-3).largest();
        assert_eq!(d.links[0].a, 0.5);
        assert_eq!(d.links[1].axes.get(Axis::Ry), Range::new(-3.0, 3.0));
    }

    #[test]
    fn largest_shortened_drops_each_removable_link_once() {
        let template = Design {
            links: vec![LinkDesign::default(); 4],
            ..space(0.0).template().clone()
        };
        let var = |link, param, lower, upper| Variable {
            link,
            param,
            lower,
            upper,
        };
        let s = DesignSpace::new(
            template,
            vec![
                var(1, Param::A, 0.0, 0.5),
                var(1, Param::D, -0.3, 0.1),
                var(2, Param::A, 0.1, 0.4), // cannot be removed: a ≥ 0.1
                var(3, Param::A, 0.0, 0.2),
                var(3, Param::Max(Axis::Ry), 0.0, 3.0),
                var(4, Param::Max(Axis::Ry), 0.0, 3.0), // no free length
            ],
            1e-3,
        )
        .unwrap();
        let largest = s.largest();
        let shortened = s.largest_shortened();
        assert_eq!(shortened.len(), 2, "links 1 and 3 only");
        assert_eq!(
            (shortened[0].links[0].a, shortened[0].links[0].d),
            (0.0, 0.0)
        );
        assert_eq!(shortened[1].links[2].a, 0.0);
        for (d, removed) in shortened.iter().zip([0, 2]) {
            for k in 0..4 {
                if k != removed {
                    assert_eq!(d.links[k], largest.links[k], "link {} kept as is", k + 1);
                }
            }
            assert_eq!(
                d.links[removed].axes, largest.links[removed].axes,
                "joints kept"
            );
        }
    }

    #[test]
    fn bad_bounds_are_errors_naming_the_variable() {
        let template = space(0.0).template().clone();
        let e = DesignSpace::new(
            template,
            vec![Variable {
                link: 1,
                param: Param::A,
                lower: 1.0,
                upper: 0.0,
            }],
            0.0,
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("link1.a"), "{e}");
    }
}
