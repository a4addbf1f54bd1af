//! `rigport verify`: whether a candidate file plays like a reference file, in any two
//! formats rigport reads, and where it does not.
//!
//! Both are loaded as every command loads its input, seen +Y up in metres (as
//! [`rigport_model::SceneFrame::model_to_gltf`] defines it), and evaluated by
//! `rigport-eval` (skin, morph weights, clips) at the same times; `rigport-compare` pairs
//! their vertices and measures the deviations. Joints pair by name (the retarget naming
//! rule), meshes and clips by name then order, vertices by index or source vertex when
//! those agree at rest, else by nearest rest position. A candidate that is the reference
//! scaled, turned or moved as a whole (a unit, an up axis, a placement: fitted on the
//! paired joints at rest) or whose clip plays at a time offset is reported as exactly
//! that, with what deviates beyond it.
//!
//! [`run`] is the whole pipeline; [`crate::verify()`] is the same function.

mod pairing;
mod picture;
mod text;

use std::path::PathBuf;

use rigport_compare::deviation::{ClipDeviation, MeshPair};
use rigport_compare::frames::{Sampling, compare_frames, find_time_offset};
use rigport_compare::glam::{DMat4, DVec3};
use rigport_compare::side::{Posed, Scratch, Side};
use rigport_compare::similarity::{self, Similarity};
use rigport_compare::vertex_map::map_vertices;
use rigport_eval::sample::{CompiledClip, FrameGrid};
use rigport_model::Asset;

use crate::load::Input;
use crate::outputs::{check_not_read, extension};
use crate::progress::{Progress, step};
use crate::{PipelineError, Report};

/// The default tolerance: deviations up to this fraction of the reference's bounding-box
/// diagonal pass (1e-5: what float32 data written and read back through glTF and USD
/// keeps on every corpus asset, with room to spare).
///
/// ```
/// assert_eq!(rigport_pipeline::verify::DEFAULT_TOLERANCE, 1e-5);
/// ```
pub const DEFAULT_TOLERANCE: f64 = 1e-5;

/// Which clips are compared.
///
/// ```
/// use rigport_pipeline::verify::Clips;
/// assert_eq!(Clips::default(), Clips::First);
/// ```
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub enum Clips {
    /// The reference's first clip (the rest pose without clips).
    #[default]
    First,
    /// The reference's clip of this name.
    Named(String),
    /// Every paired clip.
    All,
}

impl Clips {
    /// The choice a command line's `--clip NAME` and `--all-clips` make.
    ///
    /// ```
    /// use rigport_pipeline::verify::Clips;
    /// assert_eq!(Clips::from_flags(None, true), Clips::All);
    /// assert_eq!(Clips::from_flags(Some("walk"), false), Clips::Named("walk".into()));
    /// ```
    pub fn from_flags(name: Option<&str>, all: bool) -> Self {
        match (name, all) {
            (Some(name), _) => Self::Named(name.to_string()),
            (None, true) => Self::All,
            (None, false) => Self::First,
        }
    }
}

/// When the clips are compared.
///
/// ```
/// use rigport_pipeline::verify::Times;
/// assert_eq!(Times::default(), Times::KeyUnion);
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Times {
    /// At every key time of either clip.
    #[default]
    KeyUnion,
    /// Every `1 / fps` seconds from the earlier start to the later end.
    Fps(f32),
    /// At the key times both clips share (the reference's when they share none).
    AtKeys,
}

impl Times {
    /// The choice a command line's `--fps F` and `--at-keys` make.
    ///
    /// ```
    /// use rigport_pipeline::verify::Times;
    /// assert_eq!(Times::from_flags(Some(30.0), false), Times::Fps(30.0));
    /// assert_eq!(Times::from_flags(None, true), Times::AtKeys);
    /// ```
    pub fn from_flags(fps: Option<f32>, at_keys: bool) -> Self {
        match (fps, at_keys) {
            (Some(fps), _) => Self::Fps(fps),
            (None, true) => Self::AtKeys,
            (None, false) => Self::KeyUnion,
        }
    }
}

/// What `verify` compares, and how strictly.
///
/// ```
/// use rigport_pipeline::verify::{Clips, VerifyOptions};
/// use rigport_pipeline::load::Input;
/// let options = VerifyOptions::new(Input::new(vec!["walk.glb".into()]));
/// assert_eq!((options.clips, options.tolerance), (Clips::First, 1e-5));
/// ```
#[derive(Clone, Debug)]
pub struct VerifyOptions {
    /// The candidate file(s).
    pub candidate: Input,
    /// Which clips.
    pub clips: Clips,
    /// When.
    pub times: Times,
    /// Deviations up to this fraction of the reference's diagonal pass.
    pub tolerance: f64,
    /// The report as JSON (in [`Report::output`]) instead of text (in
    /// [`Report::summary`]).
    pub json: bool,
    /// A PNG of the worst frame: the reference coloured by deviation, with a colour scale.
    pub picture: Option<PathBuf>,
}

impl VerifyOptions {
    /// `candidate` against the first clip, at both clips' key times, within
    /// [`DEFAULT_TOLERANCE`], as text, without a picture.
    ///
    /// ```
    /// use rigport_pipeline::verify::VerifyOptions;
    /// let options = VerifyOptions::new(rigport_pipeline::load::Input::new(vec!["b.usdz".into()]));
    /// assert!(!options.json && options.picture.is_none());
    /// ```
    pub fn new(candidate: Input) -> Self {
        Self {
            candidate,
            clips: Clips::First,
            times: Times::KeyUnion,
            tolerance: DEFAULT_TOLERANCE,
            json: false,
            picture: None,
        }
    }
}

/// The verdict and the report.
///
/// ```
/// use rigport_pipeline::verify::{VerifyOptions, run};
/// use rigport_pipeline::{load::Input, progress::Silent};
///
/// let bvh = Input::new(vec!["../../fixtures/bvh/end_sites.bvh".into()]);
/// let same = run(&bvh, &VerifyOptions::new(bvh.clone()), &Silent)?;
/// assert!(same.passed, "{:?}", same.report.summary);
/// # Ok::<(), rigport_pipeline::PipelineError>(())
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct Verification {
    /// Whether the candidate plays like the reference within the tolerance: nothing on
    /// one side only, no placement or time offset, every deviation within it.
    pub passed: bool,
    /// The report: text in `summary`, or JSON in `output`; the picture in `log`.
    pub report: Report,
}

/// A clip pair's comparison.
pub(crate) struct ClipResult {
    /// Reference and candidate clip indices (`None`: the rest pose).
    pub clips: (Option<usize>, Option<usize>),
    /// Times compared (seconds, reference clock).
    pub times: Vec<f32>,
    /// How the times were chosen.
    pub times_kind: Times,
    /// The candidate's time offset found, if any.
    pub offset: Option<f32>,
    /// The deviations (at that offset).
    pub deviation: ClipDeviation,
    /// Within the tolerance.
    pub passed: bool,
}

/// Everything the report says.
pub(crate) struct Findings<'a> {
    pub labels: (String, String),
    pub assets: (&'a Asset, &'a Asset),
    pub diagonal: f64,
    pub tolerance: f64,
    pub joints: pairing::Paired,
    pub meshes: pairing::Paired,
    pub mesh_pairs: Vec<MeshPair>,
    pub morphs_only: Vec<(usize, Vec<String>, Vec<String>)>,
    pub clips: pairing::Paired,
    pub placement: Option<Similarity>,
    pub results: Vec<ClipResult>,
}

impl Findings<'_> {
    /// The distance within the tolerance (metres).
    pub(crate) fn within(&self) -> f64 {
        self.tolerance * self.diagonal
    }

    /// The verdict.
    pub(crate) fn passed(&self) -> bool {
        self.placement.is_none()
            && self.meshes.only_reference.is_empty()
            && self.meshes.only_candidate.is_empty()
            && self.clips.only_reference.is_empty()
            && self.clips.only_candidate.is_empty()
            && self.morphs_only.is_empty()
            && self.results.iter().all(|r| r.passed && r.offset.is_none())
    }
}

/// Compares `options.candidate` with `reference`.
///
/// ```
/// use rigport_pipeline::verify::{VerifyOptions, run};
/// use rigport_pipeline::{convert, convert::ConvertOptions, load::Input, progress::Silent, write::Output};
///
/// let dir = tempfile::tempdir()?;
/// let usdz = dir.path().join("walk.usdz");
/// let bvh = Input::new(vec!["../../fixtures/bvh/end_sites.bvh".into()]);
/// convert(&bvh, &ConvertOptions { output: Output::new(&usdz), ..Default::default() }, &Silent)?;
/// let verdict = run(&bvh, &VerifyOptions::new(Input::new(vec![usdz])), &Silent)?;
/// assert!(verdict.passed, "{:?}", verdict.report.summary);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// # Errors
/// A picture that is not `.png` (a usage error) or that is an input; either input
/// unreadable; a clip not in the reference; a side that cannot be evaluated; an
/// unwritable picture.
pub fn run(
    reference: &Input,
    options: &VerifyOptions,
    progress: &dyn Progress,
) -> Result<Verification, PipelineError> {
    if let Some(picture) = &options.picture {
        if extension(picture) != "png" {
            return Err(PipelineError::Usage(format!(
                "{}: the picture is a PNG; use the .png extension",
                picture.display()
            )));
        }
        let candidate_files = options.candidate.read_files();
        let extra: Vec<&std::path::Path> = candidate_files.iter().map(|p| p.as_path()).collect();
        check_not_read(reference, picture, &extra)?;
    }
    let (ref_plan, ref_in) = reference.load_single(progress, "reading the reference")?;
    progress.warnings(&ref_in.warnings)?;
    let (cand_plan, cand_in) = options
        .candidate
        .load_single(progress, "reading the candidate")?;
    progress.warnings(&cand_in.warnings)?;
    let labels = (ref_plan.label(), cand_plan.label());
    let findings = step(progress, "comparing", || {
        compare(&ref_in.asset, &cand_in.asset, labels, options)
    })?;
    let mut report = Report::default();
    let mut marks = Vec::new();
    if let Some(path) = &options.picture {
        marks = step(progress, "drawing", || picture::write(&findings, path))?;
        report.log.push(format!(
            "wrote {} ({} vertices ringed)",
            path.display(),
            marks.len()
        ));
    }
    if options.json {
        report.output = Some(text::json(&findings, &marks));
    } else {
        report.summary = Some(text::summary(&findings));
    }
    Ok(Verification {
        passed: findings.passed(),
        report,
    })
}

/// A side's model space -> +Y up metres.
fn frame_of(asset: &Asset) -> DMat4 {
    asset.frame.model_to_gltf(asset.meters_per_unit)
}

/// The error of a comparison step.
fn failed(what: &str, e: rigport_compare::CompareError) -> PipelineError {
    PipelineError::step(what.to_string(), e)
}

/// Pairs, fits, maps and compares.
fn compare<'a>(
    reference: &'a Asset,
    candidate: &'a Asset,
    labels: (String, String),
    options: &VerifyOptions,
) -> Result<Findings<'a>, PipelineError> {
    let ref_side = Side::new(reference, frame_of(reference))
        .map_err(|e| failed(&format!("{}: cannot be evaluated", labels.0), e))?;
    let mut cand_side = Side::new(candidate, frame_of(candidate))
        .map_err(|e| failed(&format!("{}: cannot be evaluated", labels.1), e))?;
    let (joints, joint_pairs) = pairing::pair_joints(&reference.skeleton, &candidate.skeleton);
    let mesh_names = |a: &Asset| a.meshes.iter().map(|m| m.name.clone()).collect::<Vec<_>>();
    let (rm, cm) = (mesh_names(reference), mesh_names(candidate));
    let meshes = pairing::pair_names(&as_strs(&rm), &as_strs(&cm), true);
    let clip_names = |a: &Asset| a.clips.iter().map(|c| c.name.clone()).collect::<Vec<_>>();
    let (rc, cc) = (clip_names(reference), clip_names(candidate));
    let clips = pairing::pair_names(&as_strs(&rc), &as_strs(&cc), true);

    let rest = |side: &Side<'_>| -> Result<Posed, PipelineError> {
        let mut posed = Posed::default();
        side.evaluate(None, 0.0, true, &mut Scratch::default(), &mut posed)
            .map_err(|e| failed("the rest pose cannot be evaluated", e))?;
        Ok(posed)
    };
    let ref_rest = rest(&ref_side)?;
    let diagonal = diagonal(&ref_rest);
    let within = options.tolerance * diagonal;

    // A unit, an axis or a placement: the paired joints at rest, one carried onto the
    // other by a similarity to within the tolerance (times the scale, as the candidate's
    // numbers are that much larger).
    let cand_rest = rest(&cand_side)?;
    let (a, b): (Vec<DVec3>, Vec<DVec3>) = joint_pairs
        .iter()
        .map(|p| {
            (
                ref_rest.joint_positions[p.reference],
                cand_rest.joint_positions[p.candidate],
            )
        })
        .unzip();
    let placement = similarity::fit(&a, &b)
        .filter(|(s, residual)| *residual <= within.max(1e-9) * s.scale.max(1.0))
        .map(|(s, _)| s)
        .filter(|s| !s.is_identity(within));
    if let Some(s) = placement {
        let undone = s.inverse() * cand_side.to_frame();
        cand_side = cand_side.with_frame(undone);
    }
    let cand_rest = if placement.is_some() {
        rest(&cand_side)?
    } else {
        cand_rest
    };

    let mut mesh_pairs = Vec::new();
    let mut morphs_only = Vec::new();
    for &(r, c, _) in &meshes.pairs {
        let map = map_vertices(
            (&ref_rest.positions[r], &reference.meshes[r].source_vertex),
            (&cand_rest.positions[c], &candidate.meshes[c].source_vertex),
            1e-4 * diagonal,
            1e-6 * diagonal,
        );
        mesh_pairs.push(MeshPair {
            reference: r,
            candidate: c,
            map,
        });
        let targets = |a: &Asset, m: usize| -> Vec<String> {
            a.meshes[m]
                .morph_targets
                .iter()
                .map(|t| t.name.clone())
                .collect()
        };
        let (rt, ct) = (targets(reference, r), targets(candidate, c));
        let morphs = pairing::pair_names(&as_strs(&rt), &as_strs(&ct), true);
        if !morphs.only_reference.is_empty() || !morphs.only_candidate.is_empty() {
            let names =
                |all: &[String], only: &[usize]| only.iter().map(|&k| all[k].clone()).collect();
            morphs_only.push((
                r,
                names(&rt, &morphs.only_reference),
                names(&ct, &morphs.only_candidate),
            ));
        }
    }

    let chosen: Vec<(Option<usize>, Option<usize>)> = match &options.clips {
        _ if reference.clips.is_empty() && candidate.clips.is_empty() => vec![(None, None)],
        Clips::All => clips
            .pairs
            .iter()
            .map(|&(r, c, _)| (Some(r), Some(c)))
            .collect(),
        Clips::First | Clips::Named(_) => {
            let name = match &options.clips {
                Clips::Named(n) => Some(n.as_str()),
                _ => None,
            };
            let r = reference
                .clip_index(name)
                .map_err(|e| PipelineError::Invalid(format!("{}: {e}", labels.0)))?;
            let c = r.and_then(|r| clips.pairs.iter().find(|p| p.0 == r).map(|p| p.1));
            match (r, c) {
                (Some(r), Some(c)) => vec![(Some(r), Some(c))],
                _ => Vec::new(),
            }
        }
    };
    let mut results = Vec::new();
    for (r, c) in chosen {
        results.push(compare_clip(
            (&ref_side, &cand_side),
            (r, c),
            (&joint_pairs, &mesh_pairs),
            options,
            within,
        )?);
    }
    Ok(Findings {
        labels,
        assets: (reference, candidate),
        diagonal,
        tolerance: options.tolerance,
        joints,
        meshes,
        mesh_pairs,
        morphs_only,
        clips,
        placement,
        results,
    })
}

/// One clip pair compared at its times, and at a time offset when that explains it.
fn compare_clip(
    sides: (&Side<'_>, &Side<'_>),
    clips: (Option<usize>, Option<usize>),
    pairs: (&[rigport_compare::deviation::JointPair], &[MeshPair]),
    options: &VerifyOptions,
    within: f64,
) -> Result<ClipResult, PipelineError> {
    let (rs, cs) = sides;
    let (rc, cc) = (
        compile_clip(rs.asset(), clips.0)?,
        compile_clip(cs.asset(), clips.1)?,
    );
    let times = times(rc.as_ref(), cc.as_ref(), options.times)?;
    let mut sampling = Sampling {
        reference: rc.as_ref(),
        candidate: cc.as_ref(),
        times: &times,
        offset: 0.0,
    };
    let cannot = |e| failed("the clips cannot be compared", e);
    let deviation = compare_frames(rs, cs, pairs.0, pairs.1, &sampling).map_err(cannot)?;
    let measure = |d: &ClipDeviation| {
        if d.vertices.count > 0 {
            d.vertices.max
        } else {
            d.joint_positions.max
        }
    };
    let mut result = ClipResult {
        clips,
        times_kind: options.times,
        offset: None,
        passed: measure(&deviation) <= within,
        deviation,
        times: times.clone(),
    };
    if let (false, Some(r), Some(c)) = (result.passed, rc.as_ref(), cc.as_ref()) {
        if let Some(offset) =
            find_time_offset(rs, cs, pairs.0, (r, c), &times, within).map_err(cannot)?
        {
            let slack = 1e-4 / c.fps().unwrap_or(30.0);
            let shifted: Vec<f32> = times
                .iter()
                .copied()
                .filter(|t| t + offset >= c.start() - slack && t + offset <= c.end() + slack)
                .collect();
            sampling.times = &shifted;
            sampling.offset = offset;
            let deviation = compare_frames(rs, cs, pairs.0, pairs.1, &sampling).map_err(cannot)?;
            if measure(&deviation) <= within {
                result = ClipResult {
                    offset: Some(offset),
                    passed: true,
                    deviation,
                    times: shifted.clone(),
                    ..result
                };
            }
        }
    }
    Ok(result)
}

/// Clip `k` of `asset`, compiled (`None` for `None`).
///
/// # Errors
/// The clip does not fit the skeleton.
pub(crate) fn compile_clip(
    asset: &Asset,
    k: Option<usize>,
) -> Result<Option<CompiledClip<'_>>, PipelineError> {
    k.and_then(|k| asset.clips.get(k))
        .map(|clip| {
            CompiledClip::new(clip, &asset.skeleton).map_err(|e| {
                PipelineError::step(format!("clip {:?} does not fit the skeleton", clip.name), e)
            })
        })
        .transpose()
}

/// The times to compare two clips at (`[0]` for the rest pose).
fn times(
    reference: Option<&CompiledClip<'_>>,
    candidate: Option<&CompiledClip<'_>>,
    kind: Times,
) -> Result<Vec<f32>, PipelineError> {
    let keys = |c: Option<&CompiledClip<'_>>| c.map(CompiledClip::key_times).unwrap_or_default();
    let (rk, ck) = (keys(reference), keys(candidate));
    let mut out = match kind {
        Times::KeyUnion => [rk, ck].concat(),
        Times::AtKeys => {
            let shared: Vec<f32> = rk
                .iter()
                .copied()
                .filter(|t| ck.iter().any(|u| (t - u).abs() <= 1e-5))
                .collect();
            if shared.is_empty() { rk } else { shared }
        }
        Times::Fps(fps) => {
            let all = [reference, candidate];
            let start = all
                .iter()
                .flatten()
                .map(|c| c.start())
                .fold(f32::INFINITY, f32::min);
            let end = all
                .iter()
                .flatten()
                .map(|c| c.end())
                .fold(f32::NEG_INFINITY, f32::max);
            if start.is_finite() && end.is_finite() {
                FrameGrid::new(start, end, fps)?.into_times()
            } else {
                Vec::new()
            }
        }
    };
    out.sort_by(f32::total_cmp);
    out.dedup_by(|a, b| (*a - *b).abs() <= 1e-6);
    if out.is_empty() {
        out.push(0.0);
    }
    Ok(out)
}

/// The diagonal of the bounding box of the reference's vertices at rest (of its joints
/// when it has none), at least 1e-9 m.
fn diagonal(rest: &Posed) -> f64 {
    let points: Vec<DVec3> = rest.positions.iter().flatten().copied().collect();
    let points = if points.is_empty() {
        &rest.joint_positions
    } else {
        &points
    };
    let Some(&first) = points.first() else {
        return 1e-9;
    };
    let (lo, hi) = points
        .iter()
        .fold((first, first), |(lo, hi), &p| (lo.min(p), hi.max(p)));
    (hi - lo).length().max(1e-9)
}

/// Borrowed names.
fn as_strs(names: &[String]) -> Vec<&str> {
    names.iter().map(String::as_str).collect()
}
