//! `rigport.Asset`: a rig opened as the CLI opens it, its data as numpy arrays, and what
//! can be done with it (evaluate, pose, write).

use std::path::PathBuf;

use numpy::ndarray::{Array1, Array2, Array3};
use numpy::{PyArray1, PyArray2, PyArray3, PyUntypedArrayMethods as _, ToPyArray as _};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};
use rigport_import::Imported;
use rigport_pipeline::convert::{ConvertOptions, convert_imported};
use rigport_pipeline::eval::{Evaluation, PoseSource};
use rigport_pipeline::load::Input;
use rigport_pipeline::progress::Silent;

use crate::errors::{PyProgress, to_py, usage, warn};
use crate::frames::Frames;
use crate::options::{self, InputOptions, OutputOptions};
use crate::report::Report;

/// A rig (skeleton, meshes, skins, clips) read from files as `rigport` reads them.
/// Open one with `rigport.open`.
#[pyclass(frozen, module = "rigport")]
pub struct Asset {
    /// The inputs it was read from (a command given this asset reads them again).
    pub input: Input,
    /// The asset's name in messages.
    label: String,
    /// The asset and the import's warnings.
    imported: Imported,
    /// The import's notes (`N001`).
    notes: Vec<String>,
}

/// Opens a rig: any input the CLI reads (glTF, USD, FBX, COLLADA, BVH, ASF/AMC, Pinocchio,
/// CSCI 520, or a folder of one), detected the same way, with the CLI's input options as
/// keyword arguments. Warnings of the import go to Python's `warnings` module
/// (`rigport.RigportWarning`).
///
/// Raises `rigport.InputError` for a file that cannot be read, `rigport.UsageError` for
/// an option's bad value.
#[pyfunction]
#[pyo3(signature = (
    *paths, mesh=None, skeleton=None, attachment=None, motion=Vec::new(), amc_fps=None,
    bone_mesh=true, weights=None, input_units=None, force_units=false, max_memory=None
))]
#[allow(clippy::too_many_arguments)] // one keyword argument per CLI input option
pub fn open(
    py: Python<'_>,
    paths: &Bound<'_, PyTuple>,
    mesh: Option<PathBuf>,
    skeleton: Option<PathBuf>,
    attachment: Option<PathBuf>,
    motion: Vec<PathBuf>,
    amc_fps: Option<f32>,
    bone_mesh: bool,
    weights: Option<String>,
    input_units: Option<String>,
    force_units: bool,
    max_memory: Option<u64>,
) -> PyResult<Asset> {
    let paths: Vec<PathBuf> = paths.extract()?;
    let options = InputOptions {
        mesh,
        skeleton,
        attachment,
        motion,
        amc_fps,
        bone_mesh,
        weights,
        input_units,
        force_units,
        max_memory,
    };
    let input = options::input(paths, &options)?;
    Asset::load(py, input)
}

impl Asset {
    /// Reads `input` (the GIL released), and gives its warnings to Python.
    ///
    /// # Errors
    /// As the import; a warning filter that raises.
    pub fn load(py: Python<'_>, input: Input) -> PyResult<Self> {
        let loaded = py.detach(|| input.load_single(&Silent, "reading"));
        let (plan, imported) = loaded.map_err(|e| to_py(py, &e))?;
        let (notes, warnings): (Vec<_>, Vec<_>) =
            imported.warnings.iter().partition(|w| w.is_note());
        warn(py, &warnings)?;
        Ok(Self {
            input,
            label: plan.label(),
            notes: notes.iter().map(|w| w.labelled()).collect(),
            imported,
        })
    }

    /// Evaluates as `request` asks, the GIL released.
    fn run_eval(&self, py: Python<'_>, request: &Evaluation<'_>) -> PyResult<Frames> {
        let asset = &self.imported.asset;
        let result = py.detach(|| {
            rigport_pipeline::eval::evaluate(asset, &self.label, request, &self.input.budget)
        });
        let (arrays, clip) = result.map_err(|e| to_py(py, &e))?;
        Frames::new(py, arrays, clip)
    }
}

#[pymethods]
impl Asset {
    /// Joint names, parents first (a joint's parent comes before it).
    #[getter]
    fn joints(&self) -> Vec<String> {
        let skeleton = &self.imported.asset.skeleton;
        skeleton.joints().iter().map(|j| j.name.clone()).collect()
    }

    /// Each joint's parent index (int32, J), -1 for a root.
    #[getter]
    fn parents<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i32>> {
        let skeleton = &self.imported.asset.skeleton;
        let parents: Vec<i32> = skeleton
            .parents()
            .map(|p| p.map_or(-1, |p| p.get() as i32))
            .collect();
        PyArray1::from_vec(py, parents)
    }

    /// Each joint's rest transform relative to its parent (float32, J x 4 x 4, row-major
    /// column-vector matrices: `M @ [x, y, z, 1]`), in the source's unit.
    #[getter]
    fn rest_local<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray3<f32>>> {
        let joints = self.imported.asset.skeleton.joints();
        let values: Vec<f32> = joints
            .iter()
            .flat_map(|j| j.rest_local.to_mat4().transpose().to_cols_array())
            .collect();
        let array = Array3::from_shape_vec((joints.len(), 4, 4), values)
            .map_err(|e| usage(e.to_string()))?;
        Ok(PyArray3::from_owned_array(py, array))
    }

    /// The meshes (`rigport.Mesh`), in the source's order.
    #[getter]
    fn meshes(&self, py: Python<'_>) -> Vec<Mesh> {
        let asset = &self.imported.asset;
        // The skin of each mesh as the evaluator picks it.
        let rig = rigport_eval::Rig::new(asset).ok();
        let skin = |index| rig.as_ref().and_then(|r| r.skin_of_mesh(index));
        (0..asset.meshes.len())
            .map(|index| Mesh::of(py, asset, index, skin(index)))
            .collect()
    }

    /// The clips (`rigport.Clip`), in the source's order.
    #[getter]
    fn clips(&self) -> Vec<Clip> {
        let asset = &self.imported.asset;
        asset
            .clips
            .iter()
            .map(|clip| Clip {
                name: clip.name.clone(),
                duration: clip.duration(),
                times: rigport_eval::sample::CompiledClip::new(clip, &asset.skeleton)
                    .map(|c| c.key_times())
                    .unwrap_or_default(),
            })
            .collect()
    }

    /// Metres per unit the source states, or None when it states none.
    #[getter]
    fn meters_per_unit(&self) -> Option<f64> {
        self.imported.asset.meters_per_unit
    }

    /// The source's up axis: "Y" or "Z".
    #[getter]
    fn up_axis(&self) -> &'static str {
        self.imported.asset.frame.up_axis.as_str()
    }

    /// The asset's name in messages (its files).
    #[getter]
    fn label(&self) -> String {
        self.label.clone()
    }

    /// The import's warnings as the CLI prints them (`warning[W003]: ...`).
    #[getter]
    fn warnings(&self) -> Vec<String> {
        let warnings = self.imported.warnings.iter().filter(|w| !w.is_note());
        warnings.map(|w| w.labelled()).collect()
    }

    /// The import's notes (`note[N001]: ...`): facts, nothing lost.
    #[getter]
    fn notes(&self) -> Vec<String> {
        self.notes.clone()
    }

    /// Samples a clip and skins every frame, as `rigport eval` does; the arrays equal its
    /// `.npz`'s bit for bit. `clip`: a clip's name (default: the first; none: the rest
    /// pose); `times` (seconds) or `fps` (a rate) choose the frames (default: the clip's
    /// key times); `skinning`: "lbs" or "dqs" (default: the skin's own);
    /// `max_influences`: limit the influences per vertex as a glTF would.
    #[pyo3(signature = (clip=None, times=None, fps=None, skinning=None, max_influences=None))]
    fn evaluate(
        &self,
        py: Python<'_>,
        clip: Option<String>,
        times: Option<Vec<f32>>,
        fps: Option<f32>,
        skinning: Option<String>,
        max_influences: Option<usize>,
    ) -> PyResult<Frames> {
        let request = Evaluation {
            pose: None,
            clip: clip.as_deref(),
            fps: fps.map(|f| options::positive("fps", f)).transpose()?,
            times: times.as_deref(),
            max_influences,
            skinning: options::skinning(skinning.as_deref())?,
        };
        self.run_eval(py, &request)
    }

    /// Poses the rig and skins it, as `rigport eval` with a pose file: `pose` is the
    /// same dictionary (joint name -> {"quat": [x, y, z, w]} or {"euler_deg": [x, y, z],
    /// "order": "xyz"}, applied in the joint's rest frame). One frame, at time 0.
    #[pyo3(signature = (pose, skinning=None, max_influences=None))]
    fn pose(
        &self,
        py: Python<'_>,
        pose: &Bound<'_, PyDict>,
        skinning: Option<String>,
        max_influences: Option<usize>,
    ) -> PyResult<Frames> {
        let text: String = py
            .import("json")?
            .call_method1("dumps", (pose,))?
            .extract()?;
        let origin = std::path::Path::new("pose");
        let rotations =
            rigport_import::json::pose::parse(&text, origin, &self.imported.asset.skeleton)
                .map_err(|e| to_py(py, &e.into()))?;
        let request = Evaluation {
            pose: Some(PoseSource::Rotations(&rotations)),
            max_influences,
            skinning: options::skinning(skinning.as_deref())?,
            ..Evaluation::default()
        };
        self.run_eval(py, &request)
    }

    /// Writes the asset to `path` (.glb, .gltf, .usda, .usdc or .usdz, by extension) with
    /// `rigport convert`'s options; the bytes are the CLI's. `reduce` (or a
    /// `reduce_tolerance`) reduces the clips' keys, `compress="meshopt"` compresses a glTF;
    /// with `json`, `Report.output` is the reduction's report as JSON. Returns the report.
    #[pyo3(signature = (
        path, *, max_influences=None, influences_fit=None, reduce_tolerance=None,
        reduce=false, reduce_cubic=false, compress=None, skinning=None, up_axis=None,
        meters_per_unit=None,
        root_motion="keep", root_yaw=false, root_window=None, json=false
    ))]
    #[allow(clippy::too_many_arguments)] // one keyword argument per CLI option
    fn write(
        &self,
        py: Python<'_>,
        path: PathBuf,
        max_influences: Option<u8>,
        influences_fit: Option<String>,
        reduce_tolerance: Option<f32>,
        reduce: bool,
        reduce_cubic: bool,
        compress: Option<String>,
        skinning: Option<String>,
        up_axis: Option<String>,
        meters_per_unit: Option<f64>,
        root_motion: &str,
        root_yaw: bool,
        root_window: Option<f32>,
        json: bool,
    ) -> PyResult<Report> {
        let output = options::output(
            path,
            &OutputOptions {
                max_influences,
                influences_fit,
                reduce_tolerance,
                reduce,
                reduce_cubic,
                compress,
                skinning,
                up_axis,
                meters_per_unit,
            },
        )?;
        let options = ConvertOptions {
            output,
            root_motion: options::root_motion(root_motion, root_yaw, root_window)?,
            json,
        };
        let progress = PyProgress::after(&self.imported.warnings);
        let imported = self.imported.clone();
        let result = py.detach(|| convert_imported(&self.input, imported, &options, &progress));
        let report = result.map_err(|e| progress.error(py, &e))?;
        Ok(Report::new(report, &progress))
    }

    fn __repr__(&self) -> String {
        let asset = &self.imported.asset;
        format!(
            "<rigport.Asset {}: {} joints, {} meshes, {} clips>",
            self.label,
            asset.skeleton.len(),
            asset.meshes.len(),
            asset.clips.len()
        )
    }
}

/// One mesh of an asset: its own vertices (as the source splits them for UV seams and
/// hard edges), triangles and skin weights, at rest, in the source's unit.
#[pyclass(frozen, module = "rigport")]
pub struct Mesh {
    /// The mesh's index in the asset.
    #[pyo3(get)]
    index: usize,
    /// Its name.
    #[pyo3(get)]
    name: String,
    positions: Py<PyArray2<f32>>,
    indices: Py<PyArray2<u32>>,
    normals: Option<Py<PyArray2<f32>>>,
    uvs: Option<Py<PyArray2<f32>>>,
    influence_joints: Py<PyArray2<i32>>,
    influence_weights: Py<PyArray2<f32>>,
    source_vertex: Py<PyArray1<u32>>,
}

impl Mesh {
    /// Mesh `index` of `asset` as arrays; `skin` is the binding that deforms it.
    fn of(py: Python<'_>, asset: &rigport_model::Asset, index: usize, skin: Option<usize>) -> Self {
        {
            let mesh = &asset.meshes[index];
            let v = mesh.positions.len();
            let rows = |values: Vec<f32>, width: usize| {
                let array = Array2::from_shape_vec((values.len() / width, width), values)
                    .unwrap_or_else(|_| Array2::zeros((0, width)));
                PyArray2::from_owned_array(py, array).unbind()
            };
            let flat3 = |vs: &[rigport_model::glam::Vec3]| {
                rows(vs.iter().flat_map(|p| p.to_array()).collect(), 3)
            };
            let triangles: Vec<u32> = mesh.triangles.iter().flatten().copied().collect();
            let indices = Array2::from_shape_vec((mesh.triangles.len(), 3), triangles)
                .unwrap_or_else(|_| Array2::zeros((0, 3)));
            // Skin weights as (joint, weight) rows over the skeleton's joints, zero-padded
            // to the widest vertex, as `rigport eval` dumps them.
            let skin = skin.and_then(|s| asset.skins.get(s));
            let table: Vec<Vec<(i32, f32)>> = (0..v)
                .map(|vi| match skin {
                    Some(skin) if vi >= skin.influences.vertex_count() => Vec::new(),
                    _ => rigport_export::npz::influence_row(skin, mesh.attached_to, vi),
                })
                .collect();
            let (joints, weights, k) = rigport_export::npz::padded(&table);
            let joints =
                Array2::from_shape_vec((v, k), joints).unwrap_or_else(|_| Array2::zeros((0, k)));
            Self {
                index,
                name: mesh.name.clone(),
                positions: flat3(&mesh.positions),
                indices: PyArray2::from_owned_array(py, indices).unbind(),
                normals: mesh.normals.as_deref().map(flat3),
                uvs: mesh
                    .uvs
                    .as_deref()
                    .map(|uvs| rows(uvs.iter().flat_map(|t| t.to_array()).collect(), 2)),
                influence_joints: PyArray2::from_owned_array(py, joints).unbind(),
                influence_weights: rows(weights, k.max(1)),
                source_vertex: Array1::from_vec(mesh.source_vertex.clone())
                    .to_pyarray(py)
                    .unbind(),
            }
        }
    }
}

#[pymethods]
impl Mesh {
    /// Rest positions (float32, V x 3).
    #[getter]
    fn positions(&self, py: Python<'_>) -> Py<PyArray2<f32>> {
        self.positions.clone_ref(py)
    }

    /// Triangles (uint32, T x 3), indices into `positions`.
    #[getter]
    fn indices(&self, py: Python<'_>) -> Py<PyArray2<u32>> {
        self.indices.clone_ref(py)
    }

    /// Normals (float32, V x 3), or None.
    #[getter]
    fn normals(&self, py: Python<'_>) -> Option<Py<PyArray2<f32>>> {
        self.normals.as_ref().map(|a| a.clone_ref(py))
    }

    /// Texture coordinates (float32, V x 2), or None.
    #[getter]
    fn uvs(&self, py: Python<'_>) -> Option<Py<PyArray2<f32>>> {
        self.uvs.as_ref().map(|a| a.clone_ref(py))
    }

    /// The skin weights: (joints int32 V x K, weights float32 V x K), each row's joints
    /// indexing `Asset.joints`, zero-padded; K = 0 for an unskinned mesh.
    #[getter]
    fn influences(&self, py: Python<'_>) -> (Py<PyArray2<i32>>, Py<PyArray2<f32>>) {
        (
            self.influence_joints.clone_ref(py),
            self.influence_weights.clone_ref(py),
        )
    }

    /// Each vertex's vertex in the source file (uint32, V): vertices split at UV seams
    /// share one.
    #[getter]
    fn source_vertex(&self, py: Python<'_>) -> Py<PyArray1<u32>> {
        self.source_vertex.clone_ref(py)
    }

    fn __repr__(&self, py: Python<'_>) -> String {
        let v = self.positions.bind(py).len();
        let t = self.indices.bind(py).len();
        format!(
            "<rigport.Mesh {:?}: {v} vertices, {t} triangles>",
            self.name
        )
    }
}

/// One clip of an asset.
#[pyclass(frozen, module = "rigport")]
pub struct Clip {
    /// Its name.
    #[pyo3(get)]
    name: String,
    /// Its length in seconds.
    #[pyo3(get)]
    duration: f32,
    /// The times of its keys, in seconds, sorted, as `evaluate` samples by default.
    #[pyo3(get)]
    times: Vec<f32>,
}

#[pymethods]
impl Clip {
    fn __repr__(&self) -> String {
        format!(
            "<rigport.Clip {:?}: {} s, {} key times>",
            self.name,
            self.duration,
            self.times.len()
        )
    }
}
