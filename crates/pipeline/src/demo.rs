//! `rigport demo`'s pipeline: the built-in character (`rigport_demo`) written as glTF and
//! USD, its twist with DQS baked into morph targets, its wave with a simulated skirt
//! (`rigport_demo::skirt`, morph targets), its pictures, the example keys and
//! handles files, and one picture per corpus family.
//!
//! [`run`] builds everything that is checked before writing (warnings included), gives
//! the warnings to its caller, and writes it all.

use std::path::{Path, PathBuf};

use rigport_demo::{Demo, clips, corpus, pictures};
use rigport_export::{GltfOptions, PreparedGltf, PreparedUsd, UsdOptions};
use rigport_model::{Asset, Warning};

use crate::PipelineError;
use crate::outputs::write_file;

/// The demo built in memory, ready to be written.
pub(crate) struct PreparedDemo {
    demo: Demo,
    out: PathBuf,
    gltf: PreparedGltf,
    usd: PreparedUsd,
    dqs: PreparedGltf,
    bake_reports: Vec<String>,
    skirt: PreparedGltf,
    skirt_asset: Asset,
    skirt_report: String,
    warnings: Vec<Warning>,
}

/// What [`PreparedDemo::write`] wrote.
pub(crate) struct WrittenDemo {
    /// The demo (its character and clips).
    pub demo: Demo,
    /// The example files: `wave.keys.json`, `reach.handles.json`, `twist.keys.json`.
    pub keys: [PathBuf; 3],
    /// `demo.glb`, `demo.usda` and `twist_dqs.glb`.
    pub glb: PathBuf,
    /// `demo.usda`.
    pub usd: PathBuf,
    /// `twist_dqs.glb`.
    pub dqs: PathBuf,
    /// The DQS bake's report, one line each.
    pub bake_lines: Vec<String>,
    /// `skirt.glb`: the wave clip with the skirt simulated on it.
    pub skirt: PathBuf,
    /// The cloth simulation's report.
    pub skirt_report: String,
    /// Each picture written, with what it shows.
    pub pictures: Vec<(PathBuf, String)>,
    /// One line per corpus picture written (or why there is none).
    pub corpus_lines: Vec<String>,
    /// Corpus rigs skipped, with why (warnings).
    pub corpus_skipped: Vec<String>,
}

/// Builds the demo character at `detail`, writes the example keys and handles files into
/// `out` (created), and builds the glTF, USD and DQS-baked glTF in memory; `progress` is
/// told each long step.
///
/// # Errors
/// `out` cannot be created or written; a demo or export failure (a rigport bug).
pub(crate) fn prepare(
    detail: u32,
    out: &Path,
    progress: &dyn Fn(&str),
) -> Result<PreparedDemo, PipelineError> {
    progress("building the demo character");
    let demo = rigport_demo::build(detail)?;
    std::fs::create_dir_all(out).map_err(|e| PipelineError::output(out, e))?;
    let keys = example_files(out);
    let examples = [
        clips::WAVE_KEYS_JSON,
        clips::REACH_HANDLES_JSON,
        clips::TWIST_KEYS_JSON,
    ];
    for (path, text) in keys.iter().zip(examples) {
        write_file(path, text.as_bytes())?;
    }
    let gltf =
        rigport_export::prepare_gltf(&demo.asset, &out.join("demo.glb"), &GltfOptions::default())?;
    let usd =
        rigport_export::prepare_usd(&demo.asset, &out.join("demo.usda"), &UsdOptions::default())?;
    let mut warnings = demo.warnings.clone();
    warnings.extend(gltf.warnings().iter().cloned());
    warnings.extend(usd.warnings().iter().cloned());
    let limit = usize::from(rigport_demo::DQS_INFLUENCES);
    progress("baking DQS correctives");
    let (twist, reports) = rigport_demo::twist_dqs(
        &demo,
        |skeleton, skin| rigport_export::gltf_influences(skeleton, skin, limit),
        &mut warnings,
    )?;
    let options = GltfOptions {
        max_influences: limit,
        ..GltfOptions::default()
    };
    let dqs = rigport_export::prepare_gltf(&twist, &out.join("twist_dqs.glb"), &options)?;
    warnings.extend(dqs.warnings().iter().cloned());
    let bake_reports = reports.iter().map(ToString::to_string).collect();
    progress("simulating the skirt");
    let (skirt_asset, skirt_report) = rigport_demo::skirt::bake(&demo, &mut warnings, |_, _| {})?;
    let skirt = rigport_export::prepare_gltf(
        &skirt_asset,
        &out.join("skirt.glb"),
        &GltfOptions::default(),
    )?;
    warnings.extend(skirt.warnings().iter().cloned());
    Ok(PreparedDemo {
        demo,
        out: out.to_path_buf(),
        gltf,
        usd,
        dqs,
        bake_reports,
        skirt,
        skirt_asset,
        skirt_report: skirt_report.to_string(),
        warnings,
    })
}

/// The example files' paths in `out`.
fn example_files(out: &Path) -> [PathBuf; 3] {
    ["wave.keys.json", "reach.handles.json", "twist.keys.json"].map(|f| out.join(f))
}

impl PreparedDemo {
    /// Every warning so far (the IK solve's, the writers', the bake's).
    pub(crate) fn warnings(&self) -> &[Warning] {
        &self.warnings
    }

    /// Writes the files, renders and writes the pictures, and with `corpus` one picture
    /// per corpus family into `corpus/` (a missing folder or a rig that fails is a line,
    /// not an error); `progress` is told each long step.
    ///
    /// # Errors
    /// A file cannot be written; a picture fails to render (a rigport bug).
    pub(crate) fn write(
        self,
        corpus: Option<&Path>,
        progress: &dyn Fn(&str),
    ) -> Result<WrittenDemo, PipelineError> {
        let out = &self.out;
        let (glb, usd, dqs, skirt) = (
            out.join("demo.glb"),
            out.join("demo.usda"),
            out.join("twist_dqs.glb"),
            out.join("skirt.glb"),
        );
        for (prepared, path) in [(&self.gltf, &glb), (&self.dqs, &dqs), (&self.skirt, &skirt)] {
            prepared
                .write()
                .map_err(|e| PipelineError::output(path, e))?;
        }
        self.usd
            .write()
            .map_err(|e| PipelineError::output(&usd, e))?;
        progress("rendering pictures");
        let mut pictures = Vec::new();
        let mut all = pictures::pictures(&self.demo)?;
        all.push(pictures::skirt_picture(&self.skirt_asset)?);
        for picture in all {
            let path = out.join(&picture.file);
            write_file(&path, &picture.bytes)?;
            pictures.push((path, picture.what));
        }
        let (mut corpus_lines, mut corpus_skipped) = (Vec::new(), Vec::new());
        match corpus {
            None => {}
            Some(dir) if !dir.is_dir() => corpus_lines.push(format!(
                "corpus: {} not found; no corpus pictures (give the corpus folder to draw them)",
                dir.display()
            )),
            Some(dir) => {
                progress("rendering corpus rigs");
                (corpus_lines, corpus_skipped) = corpus_pictures(dir, out)?;
            }
        }
        Ok(WrittenDemo {
            keys: example_files(out),
            demo: self.demo,
            glb,
            usd,
            dqs,
            bake_lines: (self.bake_reports.iter())
                .flat_map(|r| r.lines().map(String::from).collect::<Vec<_>>())
                .collect(),
            skirt,
            skirt_report: self.skirt_report,
            pictures,
            corpus_lines,
            corpus_skipped,
        })
    }
}

/// Renders one rig of each corpus family to `out/corpus/<family>.png` (Model1's keys
/// beside it as an example). Returns one line per picture written, and one per rig that
/// failed to load or render.
fn corpus_pictures(corpus: &Path, out: &Path) -> Result<(Vec<String>, Vec<String>), PipelineError> {
    let out = out.join("corpus");
    std::fs::create_dir_all(&out).map_err(|e| PipelineError::output(&out, e))?;
    let (mut lines, mut skipped) = (Vec::new(), Vec::new());
    for rig in &corpus::CORPUS_RIGS {
        let first = rig.files.first().copied().unwrap_or(rig.family);
        let picture = match corpus::picture(corpus, rig) {
            Ok(picture) => picture,
            Err(e) => {
                let why = crate::error::chain(&e);
                skipped.push(format!(
                    "corpus {}: skipped: {why}",
                    corpus.join(first).display()
                ));
                continue;
            }
        };
        if rig.model1_keys {
            let keys = out.join(format!("{}.keys.json", rig.family));
            write_file(&keys, clips::MODEL1_KEYS_JSON.as_bytes())?;
        }
        let path = out.join(format!("{}.png", rig.family));
        write_file(&path, &picture.png)?;
        let what = match &picture.clip {
            Some(name) => format!("clip {name:?}"),
            None => "rest pose".into(),
        };
        lines.push(format!(
            "wrote {} ({}, {what}, {} of {} frames)",
            path.display(),
            picture.label,
            picture.frames_drawn,
            picture.frames
        ));
    }
    Ok((lines, skipped))
}

/// What `rigport demo` builds, and where.
///
/// ```
/// use rigport_pipeline::demo::DemoOptions;
/// use rigport_pipeline::{demo, progress::Silent};
///
/// // The output must be a folder: a file in its place fails, and is left as it was.
/// let dir = tempfile::tempdir()?;
/// let file = dir.path().join("taken");
/// std::fs::write(&file, "not a folder")?;
/// let options = DemoOptions { detail: 1, output: file.clone(), corpus: None };
/// assert!(demo(&options, &Silent).is_err());
/// assert_eq!(std::fs::read_to_string(&file)?, "not a folder");
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Debug)]
pub struct DemoOptions {
    /// The character's detail (surface-nets cells per unit; 1 is the default).
    pub detail: u32,
    /// The folder written (created).
    pub output: PathBuf,
    /// The corpus to draw one rig per family from (`None`: no corpus pictures).
    pub corpus: Option<PathBuf>,
}

/// Builds the demo, gives its warnings to `progress` (which may refuse them: then nothing
/// but the example files is written), and writes every file and picture. The summary
/// describes the character, its clips and each file written.
///
/// ```
/// use rigport_pipeline::demo::DemoOptions;
/// use rigport_pipeline::{demo, progress::Silent};
///
/// let dir = tempfile::tempdir()?;
/// let options = DemoOptions { detail: 1, output: dir.path().join("rigport-demo"), corpus: None };
/// let report = demo(&options, &Silent)?;
/// assert!(report.summary.as_deref().is_some_and(|s| s.starts_with("rigport demo")));
/// assert!(dir.path().join("rigport-demo/demo.glb").is_file());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// # Errors
/// A demo that cannot be built or written (an output that is not a folder); refused
/// warnings.
pub fn run(
    options: &DemoOptions,
    progress: &dyn crate::progress::Progress,
) -> Result<crate::Report, PipelineError> {
    let tell = |step: &str| progress.step(step);
    let prepared = prepare(options.detail, &options.output, &tell);
    progress.step_done();
    let prepared = prepared?;
    progress.warnings(prepared.warnings())?;
    let written = prepared.write(options.corpus.as_deref(), &tell);
    progress.step_done();
    let written = written?;
    let asset = &written.demo.asset;
    let mesh = &asset.meshes[0];
    let (lo, hi) = mesh.bounds().unwrap_or_default();
    let clip = |k: usize| asset.clips.get(k).map_or(0.0, |c| c.duration());
    let mut lines = vec![
        "rigport demo: a procedural character in Pinocchio's layout".to_string(),
        format!(
            "  mesh: {} vertices, {} triangles, {:.2} m tall",
            mesh.vertex_count(),
            mesh.triangles.len(),
            hi.y - lo.y
        ),
        format!(
            "  skeleton: {} joints (one per bone, rotating about its head)",
            asset.skeleton.len()
        ),
    ];
    let [keys, reach, twist] = written.keys.each_ref().map(|p| p.display());
    lines.push(format!(
        "  clip \"wave\": {:.1} s, keyed in {keys}",
        clip(0)
    ));
    lines.push(format!(
        "  clip \"reach\": {:.1} s, IK (damped least squares) from {reach}",
        clip(1)
    ));
    lines.push(format!(
        "  clip \"twist\": {:.1} s, the left forearm twists 150 deg, keyed in {twist}",
        clip(2)
    ));
    lines.push(format!(
        "  wrote {} and {}",
        written.glb.display(),
        written.usd.display()
    ));
    let dqs = written.dqs.display();
    lines.push(format!(
        "  wrote {dqs} (clip \"twist\", DQS baked into corrective morph targets)"
    ));
    lines.extend(written.bake_lines.iter().map(|l| format!("    {l}")));
    let skirt = written.skirt.display();
    lines.push(format!(
        "  wrote {skirt} (clip \"wave\" with a skirt simulated on it, morph targets)"
    ));
    lines.push(format!("    {}", written.skirt_report));
    for (path, what) in &written.pictures {
        lines.push(format!("  wrote {} ({what})", path.display()));
    }
    lines.extend(written.corpus_lines.iter().map(|l| format!("  {l}")));
    Ok(crate::Report {
        summary: Some(lines.join("\n") + "\n"),
        notices: written
            .corpus_skipped
            .iter()
            .map(|l| format!("warning: {l}"))
            .collect(),
        ..crate::Report::default()
    })
}
