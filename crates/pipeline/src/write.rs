//! Writing an asset: key reduction, the memory check, the influence fit and the writer the
//! output's extension names ([`write_output`]). The warnings go to the caller before
//! anything is written, so a caller can refuse to write.

use std::num::NonZeroUsize;
use std::path::{Path, PathBuf};

use rigport_deform::refit::{self, asset::AssetRefit, asset::PoseSet};
use rigport_export::{GltfOptions, PreparedGltf, PreparedUsd, UsdOptions};
use rigport_model::{
    Asset, Compression, InfluencesFit, MemoryBudget, OutputFormat, OverBudget, SkinningMethod,
    UpAxis, Warning,
};

use crate::PipelineError;
use crate::compact::{self, CompactReport};
use crate::outputs::write_failure;
use crate::progress::{Progress, step};

/// How an asset is written.
///
/// ```
/// use rigport_model::SkinningMethod;
/// use rigport_pipeline::write::{Output, WriteOptions};
/// use rigport_pipeline::{convert, convert::ConvertOptions, load::Input, progress::Silent};
///
/// let dir = tempfile::tempdir()?;
/// let out = dir.path().join("bend.usda");
/// // The stage declares dual quaternion skinning for every skin.
/// let options = WriteOptions { skinning: Some(SkinningMethod::Dqs), ..WriteOptions::default() };
/// let output = Output { options, ..Output::new(&out) };
/// let input = Input::new(vec!["../../fixtures/gltf/skin_basic.glb".into()]);
/// convert(&input, &ConvertOptions { output, ..Default::default() }, &Silent)?;
/// let text = std::fs::read_to_string(&out)?;
/// assert!(text.contains(r#"primvars:skel:skinningMethod = "dualQuaternion""#));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct WriteOptions {
    /// Influences kept per vertex (glTF: 4 when `None`; USD: all when `None`).
    pub max_influences: Option<usize>,
    /// How a vertex with more influences than the limit drops the rest.
    pub influences_fit: InfluencesFit,
    /// The skinning method a `.usda` declares (`None`: each skin's own). glTF is LBS.
    pub skinning: Option<SkinningMethod>,
    /// The `upAxis` a `.usda` declares (`None`: the asset's).
    pub up_axis: Option<UpAxis>,
    /// The `metersPerUnit` a `.usda` declares (`None`: the asset's).
    pub meters_per_unit: Option<f64>,
    /// A `.usda` writes unskinned morph-animated meshes as `points.timeSamples`
    /// ([`UsdOptions::morphs_as_points`]).
    pub morphs_as_points: bool,
    /// glTF compression beyond the core ([`GltfOptions::compression`]); it reduces the
    /// clips (as [`Output::reduce`]) so that the error is measured as stored. glTF only.
    pub compression: Compression,
}

/// Where and how a command writes its asset.
///
/// ```
/// use rigport_pipeline::write::Output;
/// use rigport_pipeline::{convert, convert::ConvertOptions, load::Input, progress::Silent};
///
/// let dir = tempfile::tempdir()?;
/// // Keys that a 1 mm tolerance can drop are dropped before writing.
/// let output = Output { reduce_tolerance: Some(0.001), ..Output::new(dir.path().join("walk.glb")) };
/// let input = Input::new(vec!["../../fixtures/bvh/end_sites.bvh".into()]);
/// let report = convert(&input, &ConvertOptions { output, ..Default::default() }, &Silent)?;
/// assert!(report.log[0].starts_with("wrote "));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Output {
    /// The file; its extension names the format ([`OutputFormat::of_path`]).
    pub path: PathBuf,
    /// How the writer fits influences and labels the stage.
    pub options: WriteOptions,
    /// Reduce every clip's keys within this model-space distance (rig units) first
    /// ([`crate::compact`]); `Some` reduces even when `reduce` is `false`.
    pub reduce_tolerance: Option<f32>,
    /// Reduce every clip's keys, within `reduce_tolerance` or by default 1 mm
    /// ([`crate::compact::DEFAULT_TOLERANCE_M`]).
    pub reduce: bool,
    /// Reducing, also fit CUBICSPLINE tracks (glTF 2.0 Appendix C) where they take fewer
    /// bytes than LINEAR keys; core glTF only (USD time samples interpolate linearly, and
    /// meshopt's delta coding of LINEAR rotations beats them: on the 131_04 dance 113,432
    /// bytes LINEAR against 139,444). three.js and Babylon.js play them as written, but
    /// Blender's importer (4.5) keeps only their key values and drops the tangents: the
    /// Bandai kick at 1 mm plays 16 mm off there, 0.3 mm with LINEAR keys. So they are off
    /// by default; on fast, smooth motion they are far smaller (the dance 195,992 bytes
    /// LINEAR, 149,368 with cubic tracks).
    pub cubic: bool,
}

impl Output {
    /// `path` with the default options and no key reduction.
    ///
    /// ```
    /// let output = rigport_pipeline::write::Output::new("walk.glb");
    /// assert_eq!(output.reduce_tolerance, None);
    /// assert_eq!(output.options, Default::default());
    /// ```
    pub fn new(path: impl Into<PathBuf>) -> Self {
        Self {
            path: path.into(),
            ..Self::default()
        }
    }

    /// The format the path's extension names.
    ///
    /// ```
    /// use rigport_model::OutputFormat;
    /// use rigport_pipeline::write::Output;
    ///
    /// assert_eq!(Output::new("walk.USDZ").format()?, OutputFormat::Usdz);
    /// assert!(Output::new("walk.usd").format().unwrap_err().is_usage());
    /// assert!(Output::new("walk.fbx").format().unwrap_err().is_usage());
    /// # Ok::<(), rigport_pipeline::PipelineError>(())
    /// ```
    ///
    /// # Errors
    /// An extension rigport does not write (a usage error).
    pub fn format(&self) -> Result<OutputFormat, PipelineError> {
        crate::outputs::format_of(&self.path)
    }

    /// Whether the clips are reduced before writing.
    ///
    /// ```
    /// use rigport_pipeline::write::Output;
    /// assert!(!Output::new("a.glb").reduces());
    /// assert!(Output { reduce_tolerance: Some(0.01), ..Output::new("a.glb") }.reduces());
    /// assert!(Output { reduce: true, ..Output::new("a.glb") }.reduces());
    /// assert!(Output { cubic: true, ..Output::new("a.glb") }.reduces());
    /// ```
    pub fn reduces(&self) -> bool {
        self.reduce
            || self.cubic
            || self.reduce_tolerance.is_some()
            || self.options.compression != Compression::None
    }
}

/// Writes `asset` to `output` as the whole write step of a command: key reduction (when
/// asked), the memory check, the influence fit, the writer, and `warnings` (from import
/// and earlier steps) given to `progress` together with the writer's before anything is
/// written, so a caller that refuses them gets no file. Returns the line that says what
/// was written.
///
/// ```
/// use rigport_pipeline::write::{write_output, Output};
/// use rigport_pipeline::{progress::Silent, MemoryBudget};
///
/// let dir = tempfile::tempdir()?;
/// let out = dir.path().join("walk.usdz");
/// // An asset from anywhere (here rigport's BVH importer), with the warnings it came with.
/// let imported = rigport_import::bvh::import("../../fixtures/bvh/end_sites.bvh".as_ref())?;
/// let line = write_output(imported.asset, imported.warnings, &Output::new(&out),
///     &MemoryBudget::UNLIMITED, &Silent)?;
/// assert!(line.starts_with("wrote "), "{line}");
/// assert_eq!(&std::fs::read(&out)?[..2], b"PK");
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// # Errors
/// Over the budget; a refit or export that fails; refused warnings; an unwritable output.
pub fn write_output(
    asset: Asset,
    warnings: Vec<Warning>,
    output: &Output,
    budget: &MemoryBudget,
    progress: &dyn Progress,
) -> Result<String, PipelineError> {
    let (line, compacted) = write_output_report(asset, warnings, output, budget, progress)?;
    for line in compacted.iter().flat_map(CompactReport::lines) {
        progress.info(&line);
    }
    Ok(line)
}

/// [`write_output`], returning what compacting the clips did (when [`Output::reduces`])
/// instead of giving its lines to `progress` (example: [`CompactReport`]).
///
/// ```
/// use rigport_pipeline::write::{write_output_report, Output};
/// use rigport_pipeline::{progress::Silent, MemoryBudget};
///
/// let dir = tempfile::tempdir()?;
/// let imported = rigport_import::bvh::import("../../fixtures/bvh/end_sites.bvh".as_ref())?;
/// let (line, report) = write_output_report(imported.asset, imported.warnings,
///     &Output::new(dir.path().join("walk.usda")), &MemoryBudget::UNLIMITED, &Silent)?;
/// assert!(line.starts_with("wrote ") && report.is_none());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// # Errors
/// As [`write_output`].
pub fn write_output_report(
    mut asset: Asset,
    mut warnings: Vec<Warning>,
    output: &Output,
    budget: &MemoryBudget,
    progress: &dyn Progress,
) -> Result<(String, Option<CompactReport>), PipelineError> {
    let path = &output.path;
    let format = output.format()?;
    if output.options.compression != Compression::None && !format.is_gltf() {
        return Err(PipelineError::Invalid(format!(
            "{}: compression is a glTF extension ({}); USD stores what the reduction keeps as time samples",
            path.display(),
            output.options.compression.extension().unwrap_or("none")
        )));
    }
    if output.cubic && !(format.is_gltf() && output.options.compression == Compression::None) {
        return Err(PipelineError::Invalid(format!(
            "{}: cubic key fits are for core glTF (USD time samples interpolate linearly; with meshopt, LINEAR keys pack smaller)",
            path.display()
        )));
    }
    let mut compacted = None;
    // A second reduction, at the same time on another thread, when another encoding may
    // make a smaller file: the smaller file is kept. With meshopt and a coarser mesh grid,
    // the clips reduced for the finest grid; in core glTF, with 16-bit rotations only.
    let mut alternative = None;
    if output.reduces() {
        let tolerance = compact::tolerance_in_rig_units(&asset, output.reduce_tolerance);
        let position_error = compact::position_error(tolerance, output.options.compression);
        // (A positive error means meshopt, which only glTF takes.)
        let coarser = position_error > 0.0
            && compact::paid_grid_error(&asset, position_error, tolerance)
                .is_some_and(|e| Some(e) > compact::mesh_grid_error(&asset, 0.0));
        let core_gltf = format.is_gltf() && output.options.compression == Compression::None;
        let first = Encoding {
            position_error,
            byte_rotations: true,
        };
        let second = if coarser {
            Some(Encoding {
                position_error: 0.0,
                ..first
            })
        } else {
            core_gltf.then_some(Encoding {
                byte_rotations: false,
                ..first
            })
        };
        if let Some(second) = second {
            let mut other_asset = asset.clone();
            let (reduced, other) = rayon::join(
                || reduce_clips(&mut asset, output, first, progress),
                || reduce_clips(&mut other_asset, output, second, &crate::progress::Silent),
            );
            compacted = Some(reduced?);
            alternative = Some((other_asset, other?));
        } else {
            compacted = Some(reduce_clips(&mut asset, output, first, progress)?);
        }
    }
    let opts = &output.options;
    check_memory(&asset, path, format, budget)?;
    if format.is_gltf() && opts.max_influences.is_some_and(|k| k > 4) {
        if let Some(note) = four_influence_note(&asset) {
            progress.info(&format!("influences: {note}"));
        }
    }
    let fitted = match opts.influences_fit {
        InfluencesFit::Refit => step(progress, "refitting influences", || {
            fit_influences(&asset, opts, format)
        })?,
        InfluencesFit::Truncate => fit_influences(&asset, opts, format)?,
    };
    if let Some(report) = fitted.as_ref().and_then(|f| f.refit.as_ref()) {
        for line in describe_refit(report, opts.max_influences.unwrap_or(4)) {
            progress.info(&format!("influences: {line}"));
        }
    }
    let asset = fitted.as_ref().map_or(&asset, |f| &f.asset);
    if format.is_gltf() && opts.skinning == Some(SkinningMethod::Dqs) {
        return Err(PipelineError::Invalid("glTF defines only linear blend skinning; `rigport bake` bakes a DQS result into a glTF's morph targets, and a .usda output can declare DQS".into()));
    }
    let building = if format.is_gltf() {
        "building glTF"
    } else {
        "building USD"
    };
    let build = |asset: &Asset, reduction: Option<&Reduction>| {
        step(progress, building, || {
            prepare(asset, path, format, opts, reduction)
        })
    };
    let mut prepared = build(asset, compacted.as_ref())?;
    let mut report = None;
    // The asset whose file is written, when not `asset`.
    let mut written_asset = None;
    if let Some(mut reduction) = compacted {
        // A reduced clip never makes the file bigger: build the plain one to compare.
        let mut unreduced = asset.clone();
        unreduced.clips = std::mem::take(&mut reduction.original);
        if let Some(skeleton) = reduction.skeleton.take() {
            unreduced.skeleton = skeleton;
        }
        // A coarser position grid (meshopt) packs the mesh smaller, and 8-bit rotations
        // (core glTF) pack keys smaller, but either leaves the clips less of the bound: the
        // smaller file is kept (on the corpus the Bandai dash and walk keep the coarse
        // grid, the kick the fine one; the Bandai clips keep 8-bit leaves, the 120 fps
        // captures 16-bit rotations). The candidate takes the written asset's meshes and
        // skins (influences fitted) and its own clips and rest.
        if let Some((other_asset, other)) = alternative {
            let mut candidate_asset = asset.clone();
            candidate_asset.clips = other_asset.clips;
            candidate_asset.skeleton = other_asset.skeleton;
            let candidate = build(&candidate_asset, Some(&other))?;
            if candidate.byte_len() < prepared.byte_len() {
                prepared = candidate;
                reduction = other;
                written_asset = Some(candidate_asset);
            }
        }
        let mut compact_report = reduction.report;
        // The file the command writes without reduction or compression.
        let plain_options = WriteOptions {
            compression: Compression::None,
            ..*opts
        };
        let plain = prepare(&unreduced, path, format, &plain_options, None)?;
        compact_report.bytes_after = prepared.byte_len();
        compact_report.bytes_before = plain.byte_len();
        compact_report.reduced_written = compact_report.bytes_after <= compact_report.bytes_before;
        if !compact_report.reduced_written {
            warnings.push(Warning::Note {
                location: path.display().to_string(),
                message: format!(
                    "key reduction would write {} bytes instead of {}; the unreduced clips are written",
                    compact_report.bytes_after, compact_report.bytes_before
                ),
            });
            prepared = plain;
            written_asset = Some(unreduced);
        }
        report = Some(compact_report);
    }
    let asset = written_asset.as_ref().unwrap_or(asset);
    warnings.extend(prepared.warnings().iter().cloned());
    progress.warnings(&warnings)?;
    prepared.write()?;
    Ok((written_line(path, asset), report))
}

/// What reducing an asset's clips for an output did ([`reduce_clips`]).
struct Reduction {
    /// The clips before reduction.
    original: Vec<rigport_model::Clip>,
    /// The skeleton before constant tracks and rest noise went into it, when they did.
    skeleton: Option<rigport_model::Skeleton>,
    /// Per clip, per track, the rotation bits the reducer measured (meshopt).
    rotation_bits: Vec<Vec<u8>>,
    /// The `EXPONENTIAL` filter's mantissa bits the reducer measured (meshopt).
    vector_bits: u8,
    /// The most the mesh's position grid may move a vertex (glTF), as the clips paid for.
    position_error: f32,
    report: CompactReport,
}

/// How a reduction's file may encode what it holds: [`write_output_report`] tries two.
#[derive(Clone, Copy)]
struct Encoding {
    /// The most the mesh grid may move a vertex (see [`compact::position_error`]).
    position_error: f32,
    /// Core glTF: rotation tracks may take 8-bit components
    /// ([`rigport_anim::reduce::Codec::CORE`]).
    byte_rotations: bool,
}

/// Reduces `asset`'s clips for `output` in place (and, for glTF, moves constant tracks and
/// rest noise into the skeleton), paying out of the bound for a mesh grid whose rounding
/// is at most `encoding.position_error` (when that is at most a tenth of the bound).
///
/// # Errors
/// A clip that does not fit the skeleton, or a bad tolerance.
fn reduce_clips(
    asset: &mut Asset,
    output: &Output,
    encoding: Encoding,
    progress: &dyn Progress,
) -> Result<Reduction, PipelineError> {
    let Encoding {
        position_error,
        byte_rotations,
    } = encoding;
    let format = output.format()?;
    let tolerance = compact::tolerance_in_rig_units(asset, output.reduce_tolerance);
    // Quantized vertices (glTF) when their rounding takes at most a tenth of the bound.
    let grid_error = format
        .is_gltf()
        .then(|| compact::paid_grid_error(asset, position_error, tolerance))
        .flatten()
        .unwrap_or(0.0);
    // 16-bit rotations and meshopt filters are glTF encodings; USD writes floats.
    let vector_bits = compact::vector_bits(asset, tolerance);
    let codec = format
        .is_gltf()
        .then(|| compact::codec(output.options.compression, vector_bits, byte_rotations));
    // CUBICSPLINE fits only when asked, in core glTF (see `Output::cubic`).
    let cubic = output.cubic;
    // glTF prints rest translations in its JSON: noise under a ten-thousandth of the
    // bound is written as 0, paid out of the bound as the mesh grid is.
    let noise_below = compact::REST_NOISE * tolerance;
    let noise_error = if format.is_gltf() {
        compact::rest_noise_error(&asset.skeleton, noise_below)
    } else {
        0.0
    };
    let compacted_clips = step(progress, "reducing keys", || {
        compact::compact_clips(asset, tolerance - grid_error - noise_error, codec, cubic)
    })?;
    let rotations_i16 = compacted_clips.coded;
    let reports = compacted_clips.reports;
    let original = std::mem::replace(&mut asset.clips, compacted_clips.clips);
    // glTF drops a channel at its node's value; USD samples every joint anyway.
    let skeleton = if format.is_gltf() {
        let moved = compact::constants_into_rest(asset);
        let zeroed = compact::zero_rest_noise(asset, noise_below);
        moved.or(zeroed)
    } else {
        None
    };
    Ok(Reduction {
        original,
        skeleton,
        rotation_bits: compacted_clips.rotation_bits,
        vector_bits,
        position_error,
        report: CompactReport {
            tolerance,
            meters_per_unit: asset.meters_per_unit.unwrap_or(1.0),
            rotations_i16,
            mesh_grid_error: grid_error,
            compression: format!("{:?}", output.options.compression).to_lowercase(),
            clips: reports,
            ..CompactReport::default()
        },
    })
}

/// "wrote PATH: J joints, M meshes (V vertices), S skins, C clips (each clip's name,
/// duration and keys)".
fn written_line(path: &Path, asset: &Asset) -> String {
    let vertices: usize = asset.meshes.iter().map(|m| m.vertex_count()).sum();
    let frames: Vec<String> = asset
        .clips
        .iter()
        .map(|c| {
            let keys = c.tracks.iter().map(|t| t.times.len()).max().unwrap_or(0);
            format!("{:?} {:.3} s, {keys} keys", c.name, c.duration())
        })
        .collect();
    format!(
        "wrote {}: {} joints, {} meshes ({} vertices), {} skins, {} clips{}",
        path.display(),
        asset.skeleton.len(),
        asset.meshes.len(),
        vertices,
        asset.skins.len(),
        asset.clips.len(),
        if frames.is_empty() {
            String::new()
        } else {
            format!(" ({})", frames.join("; "))
        }
    )
}

/// Checks that writing `asset` to `path` as `format` fits `budget`.
///
/// # Errors
/// An [`OverBudget`] saying what would be written.
pub(crate) fn check_memory(
    asset: &Asset,
    path: &Path,
    format: OutputFormat,
    budget: &MemoryBudget,
) -> Result<(), OverBudget> {
    use rigport_export::estimate;
    let (needed, as_what) = match format {
        OutputFormat::Glb | OutputFormat::Gltf => (estimate::gltf_memory(asset), "glTF"),
        OutputFormat::Usda | OutputFormat::Usdc | OutputFormat::Usdz => {
            (estimate::usd_memory_at(asset, path), "USD")
        }
    };
    let what = format!(
        "{}: writing {} joints x {} samples and {} vertices as {as_what}",
        path.display(),
        asset.skeleton.len(),
        estimate::max_clip_samples(asset),
        asset
            .meshes
            .iter()
            .map(|m| m.positions.len())
            .sum::<usize>()
    );
    budget.check(what, needed)
}

/// An asset with its influences fitted to the writer's limit.
#[derive(Clone, Debug)]
pub(crate) struct Fitted {
    /// The asset, at most the limit of influences per vertex.
    pub asset: Asset,
    /// With [`InfluencesFit::Refit`]: each skin's deviations, truncation against refit.
    pub refit: Option<AssetRefit>,
}

/// The asset with at most `opts.max_influences` per vertex as `opts.influences_fit` asks
/// (glTF: 4 by default; USD: all unless given), or `None` when the writer's own limiting
/// (glTF truncation) does or nothing exceeds the limit.
///
/// # Errors
/// A limit of 0, or a refit whose clips or skins do not fit the skeleton.
pub(crate) fn fit_influences(
    asset: &Asset,
    opts: &WriteOptions,
    format: OutputFormat,
) -> Result<Option<Fitted>, PipelineError> {
    let k = match (format, opts.max_influences) {
        (format, None) if format.is_usd() => return Ok(None),
        (_, limit) => limit.unwrap_or(4),
    };
    let k = NonZeroUsize::new(k)
        .ok_or_else(|| PipelineError::Invalid("keep at least 1 influence per vertex".into()))?;
    if asset
        .skins
        .iter()
        .all(|s| s.influences.max_per_vertex() <= k.get())
    {
        return Ok(None);
    }
    let mut fitted = asset.clone();
    let refit = match opts.influences_fit {
        InfluencesFit::Truncate if format.is_gltf() => return Ok(None),
        InfluencesFit::Truncate => {
            for skin in &mut fitted.skins {
                skin.influences = rigport_model::Influences::from_rows(
                    skin.influences
                        .rows()
                        .map(|r| refit::truncate_row(r, k.get())),
                );
            }
            None
        }
        InfluencesFit::Refit => Some(refit::asset::refit_asset(&mut fitted, k)?),
    };
    Ok(Some(Fitted {
        asset: fitted,
        refit,
    }))
}

/// With more than 4 influences kept for glTF, the note that most viewers read only the
/// first set: `None` when no vertex of `asset` carries more than 4 weights.
pub(crate) fn four_influence_note(asset: &Asset) -> Option<String> {
    let eps = rigport_model::conventions::WEIGHT_EPSILON;
    let over = (asset.skins.iter().flat_map(|s| s.influences.rows()))
        .filter(|r| r.iter().filter(|i| i.weight > eps).count() > 4)
        .count();
    (over > 0).then(|| format!("{over} vertices need more than 4 influences; three.js, model-viewer, Filament, Bevy and Unity read only JOINTS_0/WEIGHTS_0 (each vertex's 4 largest weights) and show them otherwise than Babylon.js, Godot 4 and the Khronos sample viewer, which read 8"))
}

/// One line per refitted skin: its deviation from all weights, truncation against refit,
/// relative to the mesh's bounding-box diagonal.
pub(crate) fn describe_refit(report: &AssetRefit, k: usize) -> Vec<String> {
    let poses = match report.pose_set {
        PoseSet::Clips => "the clips' frames",
        PoseSet::RangeOfMotion => "a range of motion",
    };
    report.skins.iter().map(|s| {
        let rel = |d: f64| d / s.diagonal.max(f64::MIN_POSITIVE);
        format!(
            "skin {} refitted to {k} per vertex over {} poses ({poses}): deviation from all weights, max {:.2e} -> {:.2e}, RMS {:.2e} -> {:.2e} of the diagonal (truncation -> refit); {} vertices changed",
            s.skin, report.poses, rel(s.truncated.max), rel(s.refit.max),
            rel(s.truncated.rms), rel(s.refit.rms), s.changed
        )
    }).collect()
}

/// A file built in memory, ready to be written.
pub(crate) struct Prepared {
    file: PreparedFile,
    path: PathBuf,
}

/// The writers' prepared files.
enum PreparedFile {
    Gltf(PreparedGltf),
    Usd(PreparedUsd),
}

impl Prepared {
    /// The bytes [`Prepared::write`] writes.
    pub(crate) fn byte_len(&self) -> u64 {
        match &self.file {
            PreparedFile::Gltf(p) => p.byte_len(),
            PreparedFile::Usd(p) => p.byte_len(),
        }
    }

    /// The writer's warnings (lossy or repairing steps), before anything is written.
    pub(crate) fn warnings(&self) -> &[Warning] {
        match &self.file {
            PreparedFile::Gltf(p) => p.warnings(),
            PreparedFile::Usd(p) => p.warnings(),
        }
    }

    /// Writes the file (and those beside it) atomically.
    ///
    /// # Errors
    /// An output error naming the file that failed.
    pub(crate) fn write(self) -> Result<(), PipelineError> {
        match self.file {
            PreparedFile::Gltf(p) => p.write(),
            PreparedFile::Usd(p) => p.write(),
        }
        .map_err(|e| write_failure(e, &self.path))
    }
}

/// Builds `asset` as `format` for `path` in memory (the influences as the writer limits
/// them; see [`fit_influences`] for a fit first), with glTF values stored as the
/// `reduction` measured them: rotations as 16-bit integers, meshopt's bits per rotation
/// track and for translations, and the skinned meshes quantized on a grid whose rounding
/// it paid for (`None`: as they are, floats).
///
/// # Errors
/// The asset cannot be exported (the message names it).
fn prepare(
    asset: &Asset,
    path: &Path,
    format: OutputFormat,
    opts: &WriteOptions,
    reduction: Option<&Reduction>,
) -> Result<Prepared, PipelineError> {
    // A long USD text is staged beside the output as it is built: failing to write it is
    // an output error, like a failing write.
    let failed = |e| match e {
        e @ rigport_export::ExportError::Io { .. } => write_failure(e, path),
        e => PipelineError::step(format!("cannot export {:?}", asset.name), e),
    };
    let file = match format {
        OutputFormat::Glb | OutputFormat::Gltf => {
            let opts = GltfOptions {
                max_influences: opts.max_influences.unwrap_or(4),
                compact: reduction.is_some_and(|r| r.report.rotations_i16),
                quantize_mesh: reduction.is_some_and(|r| r.report.mesh_grid_error > 0.0),
                position_error: reduction.map_or(0.0, |r| r.position_error),
                compression: opts.compression,
                rotation_bits: reduction.map_or_else(Vec::new, |r| r.rotation_bits.clone()),
                vector_bits: reduction.map_or(0, |r| r.vector_bits),
            };
            PreparedFile::Gltf(rigport_export::prepare_gltf(asset, path, &opts).map_err(failed)?)
        }
        OutputFormat::Usda | OutputFormat::Usdc | OutputFormat::Usdz => {
            let opts = UsdOptions {
                skinning: opts.skinning,
                up_axis: opts.up_axis,
                meters_per_unit: opts.meters_per_unit,
                morphs_as_points: opts.morphs_as_points,
            };
            PreparedFile::Usd(rigport_export::prepare_usd(asset, path, &opts).map_err(failed)?)
        }
    };
    Ok(Prepared {
        file,
        path: path.to_path_buf(),
    })
}
