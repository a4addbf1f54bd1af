//! Root motion for the commands that write clips (`convert`, `retarget`, `retime`): the
//! hips found by the body's structure, then `rigport-anim`'s
//! [`root_motion`] job on every clip, and its
//! travel as report lines and JSON.
//!
//! The options are the job's own ([`RootMotionOptions`]); [`RootMotion::Keep`] (the
//! default) does nothing at all, so outputs stay byte for byte as without it.

use rigport_anim::root_motion::{RootMotion, RootMotionOptions, RootMotionReport, root_motion};
use rigport_model::{Asset, JointIndex};
use serde_json::{Value, json};

use crate::PipelineError;

/// What [`apply`] did: the job's report, the hips it measured and how they were found.
///
/// ```
/// use rigport_anim::root_motion::{RootMotion, RootMotionOptions};
/// use rigport_pipeline::root_motion::apply;
///
/// let mut asset = rigport_import::bvh::import("../../fixtures/bvh/end_sites.bvh".as_ref())?.asset;
/// let options = RootMotionOptions { mode: RootMotion::InPlace, ..Default::default() };
/// let done = apply(&mut asset, &options)?.expect("not keep");
/// assert_eq!((done.hips.as_str(), done.found_by), ("Hips", "the skeleton's root"));
/// assert_eq!(done.report.travel.len(), 1);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct RootMotionDone {
    /// The mode applied.
    pub mode: RootMotion,
    /// The travel per clip and the joint that carries it.
    pub report: RootMotionReport,
    /// The name of the joint measured as the hips.
    pub hips: String,
    /// How it was found: `"body structure"`, or `"the skeleton's root"` when the skeleton
    /// shows no legs.
    pub found_by: &'static str,
    /// The name of the joint carrying the travel (extract), if any.
    pub root: Option<String>,
    /// Metres per length unit of the asset, when known (the travel is reported in metres
    /// then).
    pub meters_per_unit: Option<f64>,
}

/// Changes the root motion of every clip of `asset` as `options` say; `Ok(None)` for
/// [`RootMotion::Keep`], which leaves the asset untouched. The hips are the `Hips` role of
/// the body the skeleton's structure shows (`rigport_ik::retarget::find_body`, read in the
/// first clip's first frame when the rest pose does not stand), else the skeleton's first
/// root; up is the asset's ([`rigport_model::SceneFrame::up_in_model`]).
///
/// ```
/// use rigport_anim::root_motion::{RootMotion, RootMotionOptions};
/// use rigport_pipeline::root_motion::apply;
///
/// let mut asset = rigport_import::bvh::import("../../fixtures/bvh/end_sites.bvh".as_ref())?.asset;
/// let before = asset.clone();
/// assert!(apply(&mut asset, &RootMotionOptions::default())?.is_none());
/// assert_eq!(asset, before);
/// let extract = RootMotionOptions { mode: RootMotion::Extract, yaw: true, ..Default::default() };
/// let done = apply(&mut asset, &extract)?.expect("extracted");
/// assert_eq!(done.root.as_deref(), Some("root"));
/// assert_eq!(asset.skeleton.len(), before.skeleton.len() + 1);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// # Errors
/// A skeleton without joints; the job's errors (a clip that does not fit the skeleton, a
/// bad smoothing window).
pub fn apply(
    asset: &mut Asset,
    options: &RootMotionOptions,
) -> Result<Option<RootMotionDone>, PipelineError> {
    if options.mode == RootMotion::Keep {
        return Ok(None);
    }
    let up = asset.frame.up_in_model();
    let body = rigport_ik::retarget::find_body(&asset.skeleton, up, asset.clips.first());
    let found = body.and_then(|b| b.joint("Hips").or(Some(b.pelvis)));
    let (hips, found_by) = match found {
        Some(j) => (j, "body structure"),
        None => (
            asset.skeleton.roots().next().ok_or_else(|| {
                PipelineError::Invalid("root motion: the skeleton has no joints".into())
            })?,
            "the skeleton's root",
        ),
    };
    let hips_name = asset.skeleton.joint(hips).name.clone();
    let report = root_motion(asset, hips, up, options)
        .map_err(|e| PipelineError::step("cannot change the root motion", e))?;
    let name = |j: JointIndex| asset.skeleton.joint(j).name.clone();
    Ok(Some(RootMotionDone {
        mode: options.mode,
        root: report.root.map(name),
        report,
        hips: hips_name,
        found_by,
        meters_per_unit: asset.meters_per_unit,
    }))
}

impl RootMotionDone {
    /// The length unit of the figures, and the factor from the asset's unit to it.
    fn unit(&self) -> (&'static str, f64) {
        match self.meters_per_unit {
            Some(m) if m.is_finite() && m > 0.0 => ("m", m),
            _ => ("units", 1.0),
        }
    }

    /// One line per clip (`clip "walk": in place: travel 6.10 m in 4.30 s (1.42 m/s),
    /// turn -3.1 deg`), after one naming the hips and the root.
    ///
    /// ```
    /// use rigport_anim::root_motion::{RootMotion, RootMotionOptions};
    ///
    /// let mut asset = rigport_import::bvh::import("../../fixtures/bvh/end_sites.bvh".as_ref())?.asset;
    /// let options = RootMotionOptions { mode: RootMotion::InPlace, ..Default::default() };
    /// let done = rigport_pipeline::root_motion::apply(&mut asset, &options)?.expect("in place");
    /// let lines = done.lines();
    /// assert!(lines[0].starts_with("root motion in place: hips Hips"), "{}", lines[0]);
    /// assert!(lines[1].starts_with("clip \"end_sites\": travel 0.00 units"), "{}", lines[1]);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn lines(&self) -> Vec<String> {
        let (unit, scale) = self.unit();
        let mode = match self.mode {
            RootMotion::Keep => "kept",
            RootMotion::InPlace => "in place",
            RootMotion::Extract => "extracted",
        };
        let mut head = format!(
            "root motion {mode}: hips {} (by {})",
            self.hips, self.found_by
        );
        if let Some(root) = &self.root {
            let how = if self.report.added_joint {
                "added"
            } else {
                "existing top joint"
            };
            head.push_str(&format!(", travel on {root} ({how})"));
        }
        let mut lines = vec![head];
        for t in &self.report.travel {
            lines.push(format!(
                "clip {:?}: travel {:.2} {unit} in {:.2} s ({:.2} {unit}/s), turn {:.1} deg",
                t.clip,
                f64::from(t.distance) * scale,
                t.duration_s,
                f64::from(t.speed) * scale,
                t.turn_deg
            ));
        }
        lines
    }

    /// The report as JSON: `{"mode", "hips", "root", "unit", "clips": [{"clip",
    /// "distance", "duration_s", "speed", "turn_deg"}]}`.
    ///
    /// ```
    /// use rigport_anim::root_motion::{RootMotion, RootMotionOptions};
    ///
    /// let mut asset = rigport_import::bvh::import("../../fixtures/bvh/end_sites.bvh".as_ref())?.asset;
    /// let options = RootMotionOptions { mode: RootMotion::Extract, ..Default::default() };
    /// let done = rigport_pipeline::root_motion::apply(&mut asset, &options)?.expect("extract");
    /// let json = done.json();
    /// assert_eq!((json["mode"].as_str(), json["root"].as_str()), (Some("extract"), Some("root")));
    /// assert_eq!(json["clips"][0]["clip"], "end_sites");
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn json(&self) -> Value {
        let (unit, scale) = self.unit();
        let clips: Vec<Value> = (self.report.travel.iter())
            .map(|t| {
                json!({"clip": t.clip, "distance": f64::from(t.distance) * scale,
                    "duration_s": t.duration_s, "speed": f64::from(t.speed) * scale,
                    "turn_deg": t.turn_deg})
            })
            .collect();
        let mode = match self.mode {
            RootMotion::Keep => "keep",
            RootMotion::InPlace => "in-place",
            RootMotion::Extract => "extract",
        };
        json!({"mode": mode, "hips": self.hips, "found_by": self.found_by, "root": self.root,
            "added_joint": self.report.added_joint, "unit": unit, "clips": clips})
    }
}
