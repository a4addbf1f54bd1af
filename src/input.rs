//! Resolves input arguments into import plans and runs the importers.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use rigport_import::{asf_amc, bvh, csci520, gltf, obj, pinocchio, usda, Imported};

use crate::cli::InputArgs;

/// One asset to import.
#[derive(Debug, Clone, PartialEq)]
pub enum Plan {
    /// A glTF file.
    Gltf(PathBuf),
    /// A Pinocchio rig.
    Pinocchio {
        /// The OBJ.
        mesh: PathBuf,
        /// `skeleton.out`.
        skeleton: PathBuf,
        /// `attachment.out`.
        attachment: PathBuf,
    },
    /// A bare OBJ mesh (no rig).
    Obj(PathBuf),
    /// A USC CSCI 520 rig: its `skin.config`.
    Csci520(PathBuf),
    /// An Acclaim skeleton with its motions.
    AsfAmc {
        /// The `.asf`.
        asf: PathBuf,
        /// The `.amc` files, one clip each, in the order given.
        motions: Vec<PathBuf>,
        /// Frame rate of the motions (AMC files do not state one).
        fps: f32,
    },
    /// A BVH file (skeleton and one clip).
    Bvh(PathBuf),
    /// A USD text file with UsdSkel.
    Usda(PathBuf),
}

impl Plan {
    /// A short label for messages.
    pub fn label(&self) -> String {
        match self {
            Plan::Gltf(p) | Plan::Obj(p) | Plan::Csci520(p) | Plan::Bvh(p) | Plan::Usda(p) => {
                p.display().to_string()
            }
            Plan::Pinocchio { mesh, .. } => mesh.display().to_string(),
            Plan::AsfAmc { asf, .. } => asf.display().to_string(),
        }
    }

    /// Imports the asset.
    pub fn import(&self) -> Result<Imported> {
        Ok(match self {
            Plan::Gltf(p) => gltf::import(p)?,
            Plan::Obj(p) => obj::import(p)?,
            Plan::Csci520(p) => csci520::import(p)?.imported,
            Plan::Bvh(p) => bvh::import(p)?,
            Plan::Usda(p) => usda::import(p)?,
            Plan::AsfAmc { asf, motions, fps } => asf_amc::import(asf, motions, *fps)?,
            Plan::Pinocchio {
                mesh,
                skeleton,
                attachment,
            } => pinocchio::import(mesh, skeleton, attachment)?,
        })
    }
}

fn extension(p: &Path) -> String {
    p.extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase()
}

/// Which Pinocchio file a `.out` is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum OutKind {
    Skeleton,
    Attachment,
}

/// Tells a Pinocchio `.out` file's kind by its name (`skeleton*`, `attachment*`), else by
/// its content; `None` when neither tells (an empty file).
fn out_kind(path: &Path) -> Result<Option<OutKind>> {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    if name.contains("skel") {
        return Ok(Some(OutKind::Skeleton));
    }
    if name.contains("attach") {
        return Ok(Some(OutKind::Attachment));
    }
    looks_like_skeleton(path)
}

/// Whether a `.out` file looks like a Pinocchio skeleton (`index x y z parent` with integer
/// first and last fields) rather than an attachment (rows of weights); `None` if it has no
/// non-blank line in its first 16.
fn looks_like_skeleton(path: &Path) -> Result<Option<OutKind>> {
    use std::io::{BufRead, BufReader};
    let file =
        std::fs::File::open(path).with_context(|| format!("{}: cannot read", path.display()))?;
    for line in BufReader::new(file).lines().take(16) {
        let line = line.with_context(|| format!("{}: cannot read", path.display()))?;
        let fields: Vec<&str> = line.split_ascii_whitespace().collect();
        if fields.is_empty() {
            continue;
        }
        let skeleton = fields.len() == 5
            && fields[0].parse::<i64>().is_ok()
            && fields[4].parse::<i64>().is_ok();
        return Ok(Some(if skeleton {
            OutKind::Skeleton
        } else {
            OutKind::Attachment
        }));
    }
    Ok(None)
}

/// Resolves the arguments into one plan per asset.
///
/// Positional inputs: `.glb`/`.gltf` files are assets of their own; an `.obj` with two
/// `.out` files is a Pinocchio rig (skeleton and attachment told apart by content); a
/// folder is searched for one such set. `--mesh/--skeleton/--attachment` name the set
/// explicitly.
pub fn plans(args: &InputArgs) -> Result<Vec<Plan>> {
    let fps = amc_fps(args)?;
    let mut plans = Vec::new();
    let mut objs = Vec::new();
    let mut outs = Vec::new();
    let mut amcs = Vec::new();
    for input in &args.inputs {
        if input.is_dir() {
            plans.push(plan_folder(input, fps)?);
            continue;
        }
        match extension(input).as_str() {
            "glb" | "gltf" => plans.push(Plan::Gltf(input.clone())),
            "config" => plans.push(Plan::Csci520(input.clone())),
            "obj" => objs.push(input.clone()),
            "out" => outs.push(input.clone()),
            "bvh" => plans.push(Plan::Bvh(input.clone())),
            // Text, crate (binary) or package: the importer tells them by their bytes.
            "usda" | "usd" | "usdc" | "usdz" => plans.push(Plan::Usda(input.clone())),
            "asf" => plans.push(Plan::AsfAmc {
                asf: input.clone(),
                motions: Vec::new(),
                fps,
            }),
            "amc" => amcs.push(input.clone()),
            "" => bail!(
                "{}: no file extension; expected {EXPECTED}",
                input.display()
            ),
            other => bail!(
                "{}: unsupported input type .{other}; expected {EXPECTED}",
                input.display()
            ),
        }
    }
    amcs.extend(args.motion.iter().cloned());
    if !amcs.is_empty() {
        let mut asfs = plans.iter_mut().filter_map(|p| match p {
            Plan::AsfAmc { motions, .. } => Some(motions),
            _ => None,
        });
        match (asfs.next(), asfs.next()) {
            (Some(motions), None) => motions.extend(amcs),
            _ => bail!(
                "{}: AMC motions need exactly one .asf skeleton among the inputs",
                amcs[0].display()
            ),
        }
    } else if args.amc_fps.is_some() && !plans.iter().any(|p| matches!(p, Plan::AsfAmc { .. })) {
        bail!("--fps sets the frame rate of AMC motions and needs an .asf input; to resample a clip use `rigport retime --fps`");
    }
    let mut mesh = args.mesh.clone();
    let mut skeleton = args.skeleton.clone();
    let mut attachment = args.attachment.clone();
    if mesh.is_none() && !objs.is_empty() {
        mesh = Some(objs.remove(0));
    }
    if let Some(extra) = objs.first() {
        bail!("{}: only one .obj per Pinocchio rig", extra.display());
    }
    let mut unknown = Vec::new();
    for out in outs {
        if !out.exists() {
            bail!("{}: no such file", out.display());
        }
        let (slot, kind) = match out_kind(&out)? {
            Some(OutKind::Skeleton) => (&mut skeleton, "skeleton"),
            Some(OutKind::Attachment) => (&mut attachment, "attachment"),
            None => {
                unknown.push(out);
                continue;
            }
        };
        if slot.is_some() {
            bail!("{}: a second {kind} file was given", out.display());
        }
        *slot = Some(out);
    }
    // Files that tell nothing (empty, say) fill the free slot, so the importer can say
    // what is wrong with them.
    for out in unknown {
        if skeleton.is_none() {
            skeleton = Some(out);
        } else if attachment.is_none() {
            attachment = Some(out);
        } else {
            bail!(
                "{}: more .out files than a Pinocchio rig has",
                out.display()
            );
        }
    }
    match (mesh, skeleton, attachment) {
        (Some(mesh), Some(skeleton), Some(attachment)) => plans.push(Plan::Pinocchio {
            mesh,
            skeleton,
            attachment,
        }),
        (Some(mesh), None, None) => plans.push(Plan::Obj(mesh)),
        (None, None, None) => {}
        (mesh, skeleton, attachment) => {
            let missing: Vec<&str> = [
                ("--mesh", mesh.is_none()),
                ("--skeleton", skeleton.is_none()),
                ("--attachment", attachment.is_none()),
            ]
            .iter()
            .filter(|(_, m)| *m)
            .map(|(n, _)| *n)
            .collect();
            bail!(
                "a Pinocchio rig needs a mesh, a skeleton and an attachment; missing {}",
                missing.join(", ")
            );
        }
    }
    if plans.is_empty() {
        bail!("no input given (see --help)");
    }
    Ok(plans)
}

/// What positional inputs may be.
const EXPECTED: &str = ".glb, .gltf, .usda/.usdc/.usdz/.usd, a CSCI 520 skin.config, .obj with Pinocchio .out files, .bvh, or .asf with .amc files";

/// The AMC frame rate from `--fps`/`--amc-fps`, checked.
fn amc_fps(args: &InputArgs) -> Result<f32> {
    let fps = args.amc_fps.unwrap_or(asf_amc::DEFAULT_FPS);
    if !(fps.is_finite() && fps > 0.0) {
        bail!("--fps {fps}: the AMC frame rate must be a positive number");
    }
    Ok(fps)
}

fn plan_folder(dir: &Path, fps: f32) -> Result<Plan> {
    let config = dir.join("skin.config");
    if config.is_file() {
        return Ok(Plan::Csci520(config));
    }
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)
        .with_context(|| format!("{}: cannot read folder", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_file())
        .collect();
    entries.sort();
    let asfs: Vec<&PathBuf> = entries.iter().filter(|p| extension(p) == "asf").collect();
    let bvhs: Vec<&PathBuf> = entries.iter().filter(|p| extension(p) == "bvh").collect();
    if let [asf] = asfs.as_slice() {
        let motions = entries
            .iter()
            .filter(|p| extension(p) == "amc")
            .cloned()
            .collect();
        return Ok(Plan::AsfAmc {
            asf: asf.to_path_buf(),
            motions,
            fps,
        });
    }
    if let ([bvh], []) = (bvhs.as_slice(), asfs.as_slice()) {
        return Ok(Plan::Bvh(bvh.to_path_buf()));
    }
    let gltfs: Vec<&PathBuf> = entries
        .iter()
        .filter(|p| matches!(extension(p).as_str(), "glb" | "gltf"))
        .collect();
    let objs: Vec<&PathBuf> = entries.iter().filter(|p| extension(p) == "obj").collect();
    let mut skeletons = Vec::new();
    let mut attachments = Vec::new();
    for p in entries.iter().filter(|p| extension(p) == "out") {
        match out_kind(p)? {
            Some(OutKind::Skeleton) => skeletons.push(p),
            Some(OutKind::Attachment) | None => attachments.push(p),
        }
    }
    match (objs.as_slice(), skeletons.as_slice(), attachments.as_slice()) {
        ([mesh], [skeleton], [attachment]) => Ok(Plan::Pinocchio {
            mesh: mesh.to_path_buf(),
            skeleton: skeleton.to_path_buf(),
            attachment: attachment.to_path_buf(),
        }),
        _ if gltfs.len() == 1 && objs.is_empty() => Ok(Plan::Gltf(gltfs[0].clone())),
        _ => bail!(
            "{}: expected one .obj with one skeleton and one attachment .out file (or one .glb/.gltf); found {} .obj, {} skeleton, {} attachment, {} glTF files",
            dir.display(),
            objs.len(),
            skeletons.len(),
            attachments.len(),
            gltfs.len()
        ),
    }
}

/// Resolves the arguments into exactly one asset plan.
pub fn single_plan(args: &InputArgs) -> Result<Plan> {
    let mut plans = plans(args)?;
    if plans.len() != 1 {
        bail!("this command takes one rig; {} were given", plans.len());
    }
    Ok(plans.remove(0))
}

/// Imports a plan; unless `--no-bone-mesh`, a skeleton-only asset gets a generated bone
/// mesh (noted in the warnings) so viewers show its motion.
///
/// # Errors
/// As the importer.
pub fn load(plan: &Plan, args: &InputArgs) -> Result<Imported> {
    let mut imported = plan.import()?;
    if !args.no_bone_mesh && rigport_eval::bone_mesh::add_bone_mesh(&mut imported.asset) {
        imported.warnings.push(rigport_model::Warning::Note {
            location: plan.label(),
            message: "skeleton only: added a bone mesh (one shape per bone; --no-bone-mesh to leave it out)".into(),
        });
    }
    Ok(imported)
}

/// Resolves and imports exactly one asset.
///
/// # Errors
/// As [`single_plan`] and [`load`].
pub fn load_single(args: &InputArgs) -> Result<(Plan, Imported)> {
    let plan = single_plan(args)?;
    let imported = load(&plan, args)?;
    Ok((plan, imported))
}
