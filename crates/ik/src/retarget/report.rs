//! What a retarget returns: the clip, and the report `rigport retarget` prints (the map,
//! the scales, each limb's end-effector error, the feet and hands).

use rigport_model::{Clip, JointIndex, Skeleton, Warning};

use super::roles::{Body, ROLES};
use crate::footlock::FootReport;

/// One body role of the report: its joint in each skeleton's body and which source joint
/// the map makes drive the target's.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RoleRow {
    /// The role (one of [`ROLES`]).
    pub role: &'static str,
    /// The source joint playing it, when the source's body shows it.
    pub source: Option<String>,
    /// The target joint playing it, when the target's body shows it.
    pub target: Option<String>,
    /// The source joint the map makes drive that target joint (`None`: it keeps its rest
    /// pose).
    pub driven_by: Option<String>,
}

/// The rows of every role either body shows, in [`ROLES`] order.
pub(crate) fn role_rows(
    source: &Skeleton,
    target: &Skeleton,
    pairs: &[(JointIndex, JointIndex)],
    source_body: Option<&Body>,
    target_body: Option<&Body>,
) -> Vec<RoleRow> {
    let name = |s: &Skeleton, j: JointIndex| s.joints().get(j.get()).map(|x| x.name.clone());
    ROLES
        .iter()
        .filter_map(|&role| {
            let s = source_body.and_then(|b| b.joint(role));
            let t = target_body.and_then(|b| b.joint(role));
            if s.is_none() && t.is_none() {
                return None;
            }
            let driven_by = t
                .and_then(|t| pairs.iter().find(|(_, x)| *x == t))
                .and_then(|(s, _)| name(source, *s));
            Some(RoleRow {
                role,
                source: s.and_then(|j| name(source, j)),
                target: t.and_then(|j| name(target, j)),
                driven_by,
            })
        })
        .collect()
}

/// One limb's end-effector error.
#[derive(Clone, Debug, PartialEq)]
pub struct LimbError {
    /// The end joint's role, or its target name.
    pub label: String,
    /// The target joints of the chain, first to end.
    pub target: Vec<String>,
    /// Their source joints.
    pub source: Vec<String>,
    /// The chain's rest length in the target (sum of its segments), target units.
    pub length: f32,
    /// Largest distance, over the frames, between the end effector's offset from the
    /// chain's first joint and the source's offset scaled by the length ratio (and turned
    /// by `Q`), in target limb lengths.
    pub max_error: f32,
    /// Mean of that distance over the frames.
    pub mean_error: f32,
}

/// What [`retarget`](super::retarget()) found and did.
#[derive(Clone, Debug, PartialEq)]
pub struct RetargetReport {
    /// How the map was made.
    pub map: String,
    /// `(source joint, target joint, role)` per pair.
    pub pairs: Vec<(String, String, Option<&'static str>)>,
    /// Target joints no source joint drives (they keep their rest pose).
    pub unmapped: Vec<String>,
    /// Every body role either skeleton's structure shows, with its source and target
    /// joints (empty when neither shows a body).
    pub roles: Vec<RoleRow>,
    /// The source pose the target's rest pose is matched to: `"rest pose"`, or `"first
    /// frame"` when the source's rest pose does not stand (hips less than half a leg above
    /// the ankles).
    pub reference: &'static str,
    /// Vertical scale of the hips' path (target hip height / source hip height).
    pub scale_vertical: f32,
    /// Horizontal scale of the hips' path (target leg length / source leg length).
    pub scale_horizontal: f32,
    /// Frames (the clip's key times).
    pub frames: usize,
    /// The target's rest height (largest extent of its joints), target units.
    pub height: f32,
    /// Per limb, in target joint order of the end joints.
    pub limbs: Vec<LimbError>,
    /// Per foot of the target: contacts and slide (`before`: as transferred; `after`:
    /// planted, equal to `before` without `plant_feet`). Empty when the target's feet
    /// could not be found or the clip has one frame.
    pub feet: Vec<FootReport>,
    /// Whether the feet were planted.
    pub planted: bool,
    /// Per matched hand: its label and the largest distance from its target over the
    /// frames, in target heights.
    pub hands: Vec<(String, f32)>,
}

impl RetargetReport {
    /// The report as text: the map, the scales, a Markdown table of the limbs, the feet and
    /// hands (what `rigport retarget` prints).
    pub fn summary(&self) -> String {
        let mut lines = vec![format!(
            "map: {} ({} pairs, {} target joints unmapped); source reference: its {}; hips scaled {:.3} vertically, {:.3} horizontally; {} frames",
            self.map,
            self.pairs.len(),
            self.unmapped.len(),
            self.reference,
            self.scale_vertical,
            self.scale_horizontal,
            self.frames
        )];
        let pairs: Vec<String> = self
            .pairs
            .iter()
            .map(|(s, t, _)| format!("{s}->{t}"))
            .collect();
        lines.push(format!("mapped: {}", pairs.join(", ")));
        if !self.roles.is_empty() {
            lines.push("| role | source | target |".into());
            lines.push("| --- | --- | --- |".into());
            for r in &self.roles {
                let none = || "-".to_string();
                let target = match (&r.target, &r.driven_by) {
                    (None, _) => none(),
                    (Some(t), Some(d)) if r.source.as_ref() == Some(d) => t.clone(),
                    (Some(t), Some(d)) => format!("{t} (driven by {d})"),
                    (Some(t), None) => format!("{t} (not driven)"),
                };
                lines.push(format!(
                    "| {} | {} | {target} |",
                    r.role,
                    r.source.clone().unwrap_or_else(none)
                ));
            }
        }
        lines.push("| limb | joints | end-effector error max / mean (limb lengths) |".into());
        lines.push("| --- | --- | ---: |".into());
        for l in &self.limbs {
            lines.push(format!(
                "| {} | {} | {:.3} / {:.3} |",
                l.label,
                l.target.join(" > "),
                l.max_error,
                l.mean_error
            ));
        }
        for f in &self.feet {
            let before = if self.planted {
                format!(" (before planting {:.2e})", f.before.max)
            } else {
                String::new()
            };
            lines.push(format!(
                "foot {}: {} contacts, slide max {:.2e} of the height{before}",
                f.label,
                f.contacts.len(),
                f.after.max
            ));
        }
        for (label, e) in &self.hands {
            lines.push(format!(
                "hand {label}: largest distance from the source's scaled wrist {e:.2e} of the height"
            ));
        }
        lines.join("\n")
    }
}

/// A retargeted clip.
#[derive(Clone, Debug, PartialEq)]
pub struct Retargeted {
    /// The clip for the target skeleton (same name as the source clip).
    pub clip: Clip,
    /// The figures.
    pub report: RetargetReport,
    /// Notes (unmapped joints, feet without contacts, hands out of reach).
    pub warnings: Vec<Warning>,
}
