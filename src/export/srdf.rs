//! The SRDF of a design: the planning group of the chain and the allowed-collision matrix
//! (paper-independent; MoveIt's format), so an exported robot loads into MoveIt unchanged and an
//! FCL-based checker checks exactly the self pairs kinsynth checks.
//!
//! ```xml
//! <robot name="robot">
//!   <group name="arm"><chain base_link="base_link" tip_link="tool0"/></group>
//!   <disable_collisions link1="link1_dh" link2="link2_dh" reason="Adjacent"/>
//! </robot>
//! ```
//!
//! One `<disable_collisions>` per excluded pair of body-carrying URDF links, with the reason
//! (`Adjacent`, `Default`, `Always` or `User`; see [`crate::collision::body::acm`]). Pairs that
//! never collided in random samples stay enabled, unlike in MoveIt's setup assistant. When the
//! sampling stopped at its work limit ([`crate::limits::MAX_SELF_COLLISION_WORK`]), a comment
//! before the pairs says so: the pairs it had not decided stay enabled.

use crate::collision::body::{RobotBody, SelfCollisionConfig};
use crate::design::Design;
use crate::error::Result;
use crate::export::urdf::{BASE_LINK, TOOL_LINK};
use std::fmt::Write as _;
use std::path::Path;

/// Name of the planning group.
pub const GROUP: &str = "arm";

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// The SRDF text for the robot body `body` of an exported design, robot name `name`.
pub fn body_to_srdf(body: &RobotBody, name: &str) -> String {
    chain_body_to_srdf(body, name, BASE_LINK, TOOL_LINK)
}

/// The SRDF text for the robot body `body`, robot name `name`, whose planning group is the chain
/// from the URDF link `base` to the URDF link `tip` (for an imported robot, its own frames).
pub fn chain_body_to_srdf(body: &RobotBody, name: &str, base: &str, tip: &str) -> String {
    let mut out = String::new();
    let _ = writeln!(out, "<?xml version=\"1.0\"?>");
    let _ = writeln!(out, "<robot name=\"{}\">", escape(name));
    let _ = writeln!(
        out,
        "  <group name=\"{GROUP}\">\n    <chain base_link=\"{}\" tip_link=\"{}\"/>\n  </group>",
        escape(base),
        escape(tip)
    );
    let acm = body.acm();
    if acm.work_limited() {
        let _ = writeln!(
            out,
            "  <!-- the \"Always\" sampling stopped after {} random configurations, at its \
             work limit of {}: the pairs it had not decided stay enabled -->",
            acm.samples_taken(),
            crate::limits::MAX_SELF_COLLISION_WORK
        );
    }
    for d in acm.disabled() {
        let _ = writeln!(
            out,
            "  <disable_collisions link1=\"{}\" link2=\"{}\" reason=\"{}\"/>",
            escape(&d.link1),
            escape(&d.link2),
            d.reason.name()
        );
    }
    out.push_str("</robot>\n");
    out
}

/// The SRDF of `design` with the self-collision settings `config` (the scenario's `[robot]`
/// keys), robot name `name`.
pub fn design_to_srdf(design: &Design, config: &SelfCollisionConfig, name: &str) -> String {
    let chain = design.chain();
    let body = RobotBody::capsules(&chain, config);
    body_to_srdf(&body, name)
}

/// Writes the SRDF of `design` to `path` atomically; the robot is named after the file stem
/// (as [`crate::export::urdf::write_urdf`] names the URDF).
pub fn write_srdf(design: &Design, config: &SelfCollisionConfig, path: &Path) -> Result<()> {
    let body = RobotBody::capsules(&design.chain(), config);
    write_body_srdf(&body, None, None, path)
}

/// Writes the SRDF of the robot body `body` to `path` atomically. The planning group is the
/// chain from `group`'s base to its tip (URDF links of an imported robot), or an exported
/// design's ([`body_to_srdf`]) without one. The robot is named `name` (an imported robot's URDF
/// name: MoveIt requires the SRDF and the URDF to name the same robot), else after the file
/// stem, as [`crate::export::urdf::write_urdf`] names an exported design's URDF.
pub fn write_body_srdf(
    body: &RobotBody,
    group: Option<(&str, &str)>,
    name: Option<&str>,
    path: &Path,
) -> Result<()> {
    crate::io::write_atomic(path, body_srdf_text(body, group, name, path).as_bytes())
}

/// The text [`write_body_srdf`] writes to `path`, for a caller that writes it with others
/// ([`crate::io::Staged`]).
pub fn body_srdf_text(
    body: &RobotBody,
    group: Option<(&str, &str)>,
    name: Option<&str>,
    path: &Path,
) -> String {
    let stem = path
        .file_stem()
        .and_then(|s| s.to_str())
        .filter(|s| !s.is_empty())
        .unwrap_or("kinsynth_robot");
    let name = name.unwrap_or(stem);
    match group {
        Some((base, tip)) => chain_body_to_srdf(body, name, base, tip),
        None => body_to_srdf(body, name),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::design::{AxisRanges, LinkDesign};
    use crate::kinematics::{Axis, Placement, Range};

    fn arm(n: usize) -> Design {
        let mut axes = AxisRanges::default();
        *axes.get_mut(Axis::Rz) = Range::new(-3.0, 3.0);
        Design {
            base: Placement::default(),
            link_radius: 0.02,
            colliders_per_link: 2,
            links: (0..n)
                .map(|_| LinkDesign {
                    a: 0.3,
                    axes,
                    ..LinkDesign::default()
                })
                .collect(),
            tool: None,
        }
    }

    #[test]
    fn neighbours_are_adjacent_and_distant_links_stay_enabled() {
        let text = design_to_srdf(&arm(4), &SelfCollisionConfig::default(), "r");
        assert!(text.contains("<chain base_link=\"base_link\" tip_link=\"tool0\"/>"));
        assert!(text.contains(
            "<disable_collisions link1=\"link1_dh\" link2=\"link2_dh\" reason=\"Adjacent\"/>"
        ));
        // Links 1 and 3 are a joint apart with a body between: checked, so not listed.
        assert!(
            !text.contains("link1=\"link1_dh\" link2=\"link3_dh\""),
            "{text}"
        );
    }

    #[test]
    fn self_collision_off_disables_every_pair() {
        let text = design_to_srdf(&arm(4), &SelfCollisionConfig::off(), "r");
        assert!(text.contains(
            "<disable_collisions link1=\"link1_dh\" link2=\"link3_dh\" reason=\"User\"/>"
        ));
    }
}
