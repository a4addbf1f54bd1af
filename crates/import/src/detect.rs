//! Format detection: what each input path is (by extension, and by content where the
//! extension does not tell), and how a set of paths groups into assets, the way the
//! `rigport` CLI reads its positional inputs.
//!
//! ```
//! use rigport_import::detect::{detect, open, Inputs, Kind};
//!
//! let fixtures = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures");
//! let bvh = fixtures.join("bvh/end_sites.bvh");
//! assert_eq!(detect(&bvh)?, Kind::Bvh);
//! let assets = open(&Inputs::new(vec![bvh]))?;
//! assert_eq!(assets.len(), 1);
//! assert_eq!(assets[0].1.asset.clips.len(), 1);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::path::{Path, PathBuf};

use crate::{
    asf_amc, bvh, collada, csci520, fbx, gltf, obj, pinocchio, usda, ImportError, Imported,
};

/// What positional inputs may be.
pub const EXPECTED: &str = ".glb, .gltf, .usda/.usdc/.usdz/.usd, .fbx (binary or ASCII, also told by content), .dae/.zae (COLLADA, a .dae also told by content), a CSCI 520 skin.config, .obj with Pinocchio .out files, .bvh, or .asf with .amc files";

/// What one input path is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// A folder, searched for one asset ([`plan`]).
    Folder,
    /// `.glb` or `.gltf`.
    Gltf,
    /// A USC CSCI 520 `skin.config` (`.config`).
    Csci520,
    /// An OBJ mesh (a Pinocchio rig's mesh when `.out` files come with it).
    Obj,
    /// A Pinocchio `skeleton.out` (by name, else by content: `index x y z parent` rows).
    PinocchioSkeleton,
    /// A Pinocchio `attachment.out` (by name, else by content: rows of weights).
    PinocchioAttachment,
    /// A `.out` file whose first 16 lines are blank: neither kind can be told.
    PinocchioUnknown,
    /// A BVH file (skeleton and one clip).
    Bvh,
    /// USD text with UsdSkel.
    Usda,
    /// An Acclaim skeleton.
    Asf,
    /// An Acclaim motion.
    Amc,
    /// An FBX file, binary or ASCII (by extension, or by its first bytes whatever the
    /// extension).
    Fbx,
    /// A COLLADA document (`.dae`, or any extension when its root element is `<COLLADA>`)
    /// or package (`.zae`).
    Collada,
}

/// One asset to import.
#[derive(Debug, Clone, PartialEq)]
pub enum Source {
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
    /// A Pinocchio mesh and skeleton without an attachment, whose weights the caller
    /// computes ([`Inputs::auto_weights`]; [`Source::import`] refuses it).
    PinocchioUnweighted {
        /// The OBJ.
        mesh: PathBuf,
        /// `skeleton.out`.
        skeleton: PathBuf,
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
    /// An FBX file (binary or ASCII).
    Fbx(PathBuf),
    /// A COLLADA document or `.zae` package.
    Collada(PathBuf),
}

impl Source {
    /// A short label for messages: the main file.
    pub fn label(&self) -> String {
        match self {
            Source::Gltf(p)
            | Source::Obj(p)
            | Source::Csci520(p)
            | Source::Bvh(p)
            | Source::Usda(p)
            | Source::Fbx(p)
            | Source::Collada(p) => p.display().to_string(),
            Source::Pinocchio { mesh, .. } | Source::PinocchioUnweighted { mesh, .. } => {
                mesh.display().to_string()
            }
            Source::AsfAmc { asf, .. } => asf.display().to_string(),
        }
    }

    /// The files the import reads (for a CSCI 520 rig: the config and the files beside it).
    pub fn files(&self) -> Vec<PathBuf> {
        match self {
            Source::Gltf(p)
            | Source::Obj(p)
            | Source::Bvh(p)
            | Source::Usda(p)
            | Source::Fbx(p)
            | Source::Collada(p) => vec![p.clone()],
            Source::Csci520(config) => {
                let mut files = vec![config.clone()];
                if let Some(Ok(entries)) = config.parent().map(std::fs::read_dir) {
                    files.extend(
                        entries
                            .filter_map(Result::ok)
                            .map(|e| e.path())
                            .filter(|p| p != config && p.is_file()),
                    );
                }
                files
            }
            Source::Pinocchio {
                mesh,
                skeleton,
                attachment,
            } => vec![mesh.clone(), skeleton.clone(), attachment.clone()],
            Source::PinocchioUnweighted { mesh, skeleton } => vec![mesh.clone(), skeleton.clone()],
            Source::AsfAmc { asf, motions, .. } => {
                let mut files = vec![asf.clone()];
                files.extend(motions.iter().cloned());
                files
            }
        }
    }

    /// Imports the asset with its format's importer.
    ///
    /// # Errors
    /// As the importer.
    pub fn import(&self) -> Result<Imported, ImportError> {
        Ok(match self {
            Source::Gltf(p) => gltf::import(p)?,
            Source::Obj(p) => obj::import(p)?,
            Source::Csci520(p) => csci520::import(p)?.imported,
            Source::Bvh(p) => bvh::import(p)?,
            Source::Usda(p) => usda::import(p)?,
            Source::Fbx(p) => fbx::import(p)?,
            Source::Collada(p) => collada::import(p)?,
            Source::AsfAmc { asf, motions, fps } => asf_amc::import(asf, motions, *fps)?,
            Source::Pinocchio {
                mesh,
                skeleton,
                attachment,
            } => pinocchio::import(mesh, skeleton, attachment)?,
            Source::PinocchioUnweighted { mesh, .. } => {
                return Err(ImportError::new(
                    crate::Location::file(mesh),
                    crate::Problem::Invalid(
                        "no attachment.out: the weights must be computed (automatic weights)"
                            .into(),
                    ),
                ))
            }
        })
    }
}

/// A set of input paths, as the CLI takes them.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Inputs {
    /// Files and folders, in order.
    pub paths: Vec<PathBuf>,
    /// The Pinocchio mesh, named explicitly (`--mesh`).
    pub mesh: Option<PathBuf>,
    /// The Pinocchio skeleton, named explicitly (`--skeleton`).
    pub skeleton: Option<PathBuf>,
    /// The Pinocchio attachment, named explicitly (`--attachment`).
    pub attachment: Option<PathBuf>,
    /// More AMC motions for the one `.asf` (`--motion`).
    pub motions: Vec<PathBuf>,
    /// The AMC frame rate (`--amc-fps`; default [`asf_amc::DEFAULT_FPS`]).
    pub amc_fps: Option<f32>,
    /// A Pinocchio mesh and skeleton without an attachment are a
    /// [`Source::PinocchioUnweighted`] (`--weights auto`), not an incomplete rig.
    pub auto_weights: bool,
}

impl Inputs {
    /// Just these paths.
    pub fn new(paths: Vec<PathBuf>) -> Self {
        Self {
            paths,
            ..Self::default()
        }
    }
}

/// Why a set of inputs does not make assets. The messages name the [`Inputs`] fields, not
/// the flags of a command line that set them: a CLI names its flags itself.
#[derive(Debug, thiserror::Error)]
pub enum DetectError {
    /// A file or folder could not be read.
    #[error("{path}: cannot read{}", if *.folder { " folder" } else { "" })]
    Io {
        /// The path.
        path: String,
        /// Whether it is a folder.
        folder: bool,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// A file without an extension.
    #[error("{0}: no file extension; expected {EXPECTED}")]
    NoExtension(String),
    /// An extension no importer reads.
    #[error("{path}: unsupported input type .{extension}; expected {EXPECTED}")]
    Unsupported {
        /// The file.
        path: String,
        /// Its extension, lower case.
        extension: String,
    },
    /// AMC motions without exactly one `.asf`.
    #[error("{0}: AMC motions need exactly one .asf skeleton among the inputs")]
    AmcWithoutAsf(String),
    /// An AMC frame rate ([`Inputs::amc_fps`]) without an `.asf`.
    #[error("the frame rate of AMC motions needs an .asf input")]
    FpsWithoutAsf,
    /// A bad AMC frame rate ([`Inputs::amc_fps`]).
    #[error("{0}: the AMC frame rate must be a positive number")]
    BadAmcFps(f32),
    /// Two OBJ files.
    #[error("{0}: only one .obj per Pinocchio rig")]
    SecondObj(String),
    /// A `.out` file that does not exist.
    #[error("{0}: no such file")]
    Missing(String),
    /// A second skeleton or attachment.
    #[error("{path}: a second {kind} file was given")]
    SecondOut {
        /// The file.
        path: String,
        /// `skeleton` or `attachment`.
        kind: &'static str,
    },
    /// More `.out` files than a rig has.
    #[error("{0}: more .out files than a Pinocchio rig has")]
    TooManyOuts(String),
    /// An incomplete Pinocchio rig: the files it lacks, in [`PinocchioFile`] order.
    #[error("a Pinocchio rig needs a mesh, a skeleton and an attachment; missing {}", join(.0))]
    IncompletePinocchio(Vec<PinocchioFile>),
    /// A folder without one recognizable asset.
    #[error("{path}: expected one .obj with one skeleton and one attachment .out file (or one .glb/.gltf); found {objs} .obj, {skeletons} skeleton, {attachments} attachment, {gltfs} glTF files")]
    Folder {
        /// The folder.
        path: String,
        /// OBJ files found.
        objs: usize,
        /// Skeleton `.out` files found.
        skeletons: usize,
        /// Attachment (or unknown) `.out` files found.
        attachments: usize,
        /// glTF files found.
        gltfs: usize,
    },
    /// No input.
    #[error("no input given")]
    NoInput,
}

/// One of the three files of a Pinocchio rig ([`Inputs::mesh`], [`Inputs::skeleton`],
/// [`Inputs::attachment`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PinocchioFile {
    /// The OBJ mesh.
    Mesh,
    /// The `skeleton.out`.
    Skeleton,
    /// The `attachment.out`.
    Attachment,
}

impl std::fmt::Display for PinocchioFile {
    /// `mesh`, `skeleton` or `attachment`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::Mesh => "mesh",
            Self::Skeleton => "skeleton",
            Self::Attachment => "attachment",
        })
    }
}

fn join(files: &[PinocchioFile]) -> String {
    files
        .iter()
        .map(ToString::to_string)
        .collect::<Vec<_>>()
        .join(", ")
}

/// A path's extension, lower case (`""` without one).
fn extension(p: &Path) -> String {
    p.extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase()
}

/// What `path` is: a folder; an FBX file by its first bytes (`Kaydara FBX Binary` or
/// `; FBX`), or a COLLADA document by its root element (`<COLLADA`), whatever its
/// extension; else a file by its extension; a Pinocchio `.out` by
/// its name (`skeleton*`, `attachment*`), else by its content.
///
/// # Errors
/// An unreadable `.out` file, no or an unknown extension.
pub fn detect(path: &Path) -> Result<Kind, DetectError> {
    if path.is_dir() {
        return Ok(Kind::Folder);
    }
    let head = head_of(path);
    if fbx::is_fbx(&head) {
        return Ok(Kind::Fbx);
    }
    if collada::is_collada(&head) {
        return Ok(Kind::Collada);
    }
    let shown = || path.display().to_string();
    Ok(match extension(path).as_str() {
        "fbx" => Kind::Fbx,
        "dae" | "zae" => Kind::Collada,
        "glb" | "gltf" => Kind::Gltf,
        "config" => Kind::Csci520,
        "obj" => Kind::Obj,
        "out" => out_kind(path)?,
        "bvh" => Kind::Bvh,
        // Text, crate (binary) or package: the USD importer tells them by their bytes.
        "usda" | "usd" | "usdc" | "usdz" => Kind::Usda,
        "asf" => Kind::Asf,
        "amc" => Kind::Amc,
        "" => return Err(DetectError::NoExtension(shown())),
        other => {
            return Err(DetectError::Unsupported {
                path: shown(),
                extension: other.to_string(),
            })
        }
    })
}

/// The file's first bytes (up to 4 KiB: room for an XML prolog and comments before a
/// COLLADA root element); none for a file that cannot be read.
fn head_of(path: &Path) -> Vec<u8> {
    use std::io::Read;
    let mut head = Vec::new();
    if let Ok(file) = std::fs::File::open(path) {
        // A read error leaves what was read: detection then falls back to the extension.
        let _ = file.take(4096).read_to_end(&mut head);
    }
    head
}

/// Tells a Pinocchio `.out` file's kind by its name, else by its content.
fn out_kind(path: &Path) -> Result<Kind, DetectError> {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    if name.contains("skel") {
        return Ok(Kind::PinocchioSkeleton);
    }
    if name.contains("attach") {
        return Ok(Kind::PinocchioAttachment);
    }
    looks_like_skeleton(path)
}

/// Whether a `.out` file looks like a Pinocchio skeleton (`index x y z parent` with integer
/// first and last fields) rather than an attachment (rows of weights), from its first
/// non-blank line among the first 16.
fn looks_like_skeleton(path: &Path) -> Result<Kind, DetectError> {
    use std::io::{BufRead, BufReader};
    let io = |source| DetectError::Io {
        path: path.display().to_string(),
        folder: false,
        source,
    };
    let file = std::fs::File::open(path).map_err(io)?;
    for line in BufReader::new(file).lines().take(16) {
        let line = line.map_err(io)?;
        let fields: Vec<&str> = line.split_ascii_whitespace().collect();
        if fields.is_empty() {
            continue;
        }
        let skeleton = fields.len() == 5
            && fields[0].parse::<i64>().is_ok()
            && fields[4].parse::<i64>().is_ok();
        return Ok(if skeleton {
            Kind::PinocchioSkeleton
        } else {
            Kind::PinocchioAttachment
        });
    }
    Ok(Kind::PinocchioUnknown)
}

/// Groups the inputs into one [`Source`] per asset.
///
/// `.glb`/`.gltf`, `.usda`, `.bvh` and `skin.config` files are assets of their own; an
/// `.obj` with two `.out` files is a Pinocchio rig (skeleton and attachment told apart by
/// name or content); an `.asf` takes the `.amc` motions; a folder is searched for one
/// asset. [`Inputs::mesh`] and friends name a Pinocchio set explicitly.
///
/// # Errors
/// See [`DetectError`].
pub fn plan(inputs: &Inputs) -> Result<Vec<Source>, DetectError> {
    let fps = inputs.amc_fps.unwrap_or(asf_amc::DEFAULT_FPS);
    if !(fps.is_finite() && fps > 0.0) {
        return Err(DetectError::BadAmcFps(fps));
    }
    let mut sources = Vec::new();
    let mut objs = Vec::new();
    let mut outs = Vec::new();
    let mut amcs = Vec::new();
    for input in &inputs.paths {
        if input.is_dir() {
            sources.push(plan_folder(input, fps)?);
            continue;
        }
        // `.out` files are told apart below, after checking they exist.
        if extension(input) == "out" {
            outs.push(input.clone());
            continue;
        }
        match detect(input)? {
            Kind::Gltf => sources.push(Source::Gltf(input.clone())),
            Kind::Csci520 => sources.push(Source::Csci520(input.clone())),
            Kind::Obj => objs.push(input.clone()),
            Kind::Bvh => sources.push(Source::Bvh(input.clone())),
            Kind::Usda => sources.push(Source::Usda(input.clone())),
            Kind::Fbx => sources.push(Source::Fbx(input.clone())),
            Kind::Collada => sources.push(Source::Collada(input.clone())),
            Kind::Asf => sources.push(Source::AsfAmc {
                asf: input.clone(),
                motions: Vec::new(),
                fps,
            }),
            Kind::Amc => amcs.push(input.clone()),
            Kind::Folder
            | Kind::PinocchioSkeleton
            | Kind::PinocchioAttachment
            | Kind::PinocchioUnknown => outs.push(input.clone()),
        }
    }
    amcs.extend(inputs.motions.iter().cloned());
    if let Some(first) = amcs.first() {
        let first = first.display().to_string();
        let mut asfs = sources.iter_mut().filter_map(|p| match p {
            Source::AsfAmc { motions, .. } => Some(motions),
            _ => None,
        });
        match (asfs.next(), asfs.next()) {
            (Some(motions), None) => motions.extend(amcs),
            _ => return Err(DetectError::AmcWithoutAsf(first)),
        }
    } else if inputs.amc_fps.is_some()
        && !sources.iter().any(|p| matches!(p, Source::AsfAmc { .. }))
    {
        return Err(DetectError::FpsWithoutAsf);
    }
    let mut mesh = inputs.mesh.clone();
    let mut skeleton = inputs.skeleton.clone();
    let mut attachment = inputs.attachment.clone();
    if mesh.is_none() && !objs.is_empty() {
        mesh = Some(objs.remove(0));
    }
    if let Some(extra) = objs.first() {
        return Err(DetectError::SecondObj(extra.display().to_string()));
    }
    let mut unknown = Vec::new();
    for out in outs {
        if !out.exists() {
            return Err(DetectError::Missing(out.display().to_string()));
        }
        let (slot, kind) = match out_kind(&out)? {
            Kind::PinocchioSkeleton => (&mut skeleton, "skeleton"),
            Kind::PinocchioAttachment => (&mut attachment, "attachment"),
            _ => {
                unknown.push(out);
                continue;
            }
        };
        if slot.is_some() {
            return Err(DetectError::SecondOut {
                path: out.display().to_string(),
                kind,
            });
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
            return Err(DetectError::TooManyOuts(out.display().to_string()));
        }
    }
    match (mesh, skeleton, attachment) {
        (Some(mesh), Some(skeleton), Some(attachment)) => sources.push(Source::Pinocchio {
            mesh,
            skeleton,
            attachment,
        }),
        (Some(mesh), Some(skeleton), None) if inputs.auto_weights => {
            sources.push(Source::PinocchioUnweighted { mesh, skeleton })
        }
        (Some(mesh), None, None) => sources.push(Source::Obj(mesh)),
        (None, None, None) => {}
        (mesh, skeleton, attachment) => {
            let missing = [
                (PinocchioFile::Mesh, mesh.is_none()),
                (PinocchioFile::Skeleton, skeleton.is_none()),
                (PinocchioFile::Attachment, attachment.is_none()),
            ]
            .iter()
            .filter(|(_, m)| *m)
            .map(|(n, _)| *n)
            .collect();
            return Err(DetectError::IncompletePinocchio(missing));
        }
    }
    if sources.is_empty() {
        return Err(DetectError::NoInput);
    }
    Ok(sources)
}

/// The one asset of a folder: its `skin.config`, its one `.asf` (with every `.amc`), its
/// one `.bvh`, its Pinocchio set, or its one glTF file.
fn plan_folder(dir: &Path, fps: f32) -> Result<Source, DetectError> {
    let config = dir.join("skin.config");
    if config.is_file() {
        return Ok(Source::Csci520(config));
    }
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(|source| DetectError::Io {
            path: dir.display().to_string(),
            folder: true,
            source,
        })?
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
        return Ok(Source::AsfAmc {
            asf: asf.to_path_buf(),
            motions,
            fps,
        });
    }
    if let ([bvh], []) = (bvhs.as_slice(), asfs.as_slice()) {
        return Ok(Source::Bvh(bvh.to_path_buf()));
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
            Kind::PinocchioSkeleton => skeletons.push(p),
            _ => attachments.push(p),
        }
    }
    match (
        objs.as_slice(),
        skeletons.as_slice(),
        attachments.as_slice(),
    ) {
        ([mesh], [skeleton], [attachment]) => Ok(Source::Pinocchio {
            mesh: mesh.to_path_buf(),
            skeleton: skeleton.to_path_buf(),
            attachment: attachment.to_path_buf(),
        }),
        _ if gltfs.len() == 1 && objs.is_empty() => Ok(Source::Gltf(gltfs[0].clone())),
        _ => Err(DetectError::Folder {
            path: dir.display().to_string(),
            objs: objs.len(),
            skeletons: skeletons.len(),
            attachments: attachments.len(),
            gltfs: gltfs.len(),
        }),
    }
}

/// Why [`open`] failed.
#[derive(Debug, thiserror::Error)]
pub enum OpenError {
    /// The inputs do not group into assets.
    #[error(transparent)]
    Detect(#[from] DetectError),
    /// An asset could not be imported.
    #[error(transparent)]
    Import(#[from] ImportError),
}

/// Opens a set of inputs the way the CLI does: [`plan`], then each [`Source::import`].
///
/// # Errors
/// As [`plan`], then the first importer error.
pub fn open(inputs: &Inputs) -> Result<Vec<(Source, Imported)>, OpenError> {
    plan(inputs)?
        .into_iter()
        .map(|source| {
            let imported = source.import()?;
            Ok((source, imported))
        })
        .collect()
}
