//! `rigport.Frames`: evaluated frames as numpy arrays over the Rust buffers (no copy).

use numpy::ndarray::{Array1, Array2, Array3, Array4};
use numpy::{PyArray1, PyArray2, PyArray3, PyArray4, PyUntypedArrayMethods as _};
use pyo3::prelude::*;
use rigport_pipeline::eval::EvalArrays;

use crate::errors::usage;

/// Frames evaluated by `Asset.evaluate` or `Asset.pose`: the arrays of `rigport eval`'s
/// `.npz`, equal bit for bit, always with the frame axis (a pose is one frame at time 0,
/// where the `.npz` has no frame axis). Vertices are listed mesh by mesh, each in its
/// source vertex order (`rows` maps a mesh's own vertices to them). The arrays are views
/// of the evaluator's buffers: numpy does not copy them.
#[pyclass(frozen, module = "rigport")]
pub struct Frames {
    times: Py<PyArray1<f32>>,
    positions: Py<PyArray3<f32>>,
    joint_world: Py<PyArray4<f32>>,
    skin_matrices: Py<PyArray4<f32>>,
    rest_positions: Py<PyArray2<f32>>,
    influence_joints: Py<PyArray2<i32>>,
    influence_weights: Py<PyArray2<f32>>,
    rows: Vec<Py<PyArray1<u32>>>,
    /// The joints' names (J).
    #[pyo3(get)]
    joint_names: Vec<String>,
    /// The skinning method: "lbs" or "dqs".
    #[pyo3(get)]
    skinning: &'static str,
    /// The clip sampled, or None for a pose.
    #[pyo3(get)]
    clip: Option<String>,
}

/// A shape error as a Python error (the evaluator's sizes disagree: a bug).
fn shape(e: numpy::ndarray::ShapeError) -> PyErr {
    usage(format!("evaluated arrays of unexpected size: {e}"))
}

impl Frames {
    /// Numpy arrays that own `arrays`' buffers.
    ///
    /// # Errors
    /// Sizes that do not match (a bug).
    pub fn new(py: Python<'_>, arrays: EvalArrays, clip: Option<String>) -> PyResult<Self> {
        let (f, v, j, k) = (
            arrays.frames,
            arrays.vertices,
            arrays.joints,
            arrays.max_influences,
        );
        let owned1 = |a: Vec<f32>| PyArray1::from_owned_array(py, Array1::from_vec(a)).unbind();
        let mats = |a: Vec<f32>| -> PyResult<Py<PyArray4<f32>>> {
            let a = Array4::from_shape_vec((f, j, 4, 4), a).map_err(shape)?;
            Ok(PyArray4::from_owned_array(py, a).unbind())
        };
        let positions = Array3::from_shape_vec((f, v, 3), arrays.positions).map_err(shape)?;
        let rest = Array2::from_shape_vec((v, 3), arrays.rest_positions).map_err(shape)?;
        let joints = Array2::from_shape_vec((v, k), arrays.influence_joints).map_err(shape)?;
        let weights = Array2::from_shape_vec((v, k), arrays.influence_weights).map_err(shape)?;
        Ok(Self {
            times: owned1(arrays.times),
            positions: PyArray3::from_owned_array(py, positions).unbind(),
            joint_world: mats(arrays.joint_world)?,
            skin_matrices: mats(arrays.skin_matrices)?,
            rest_positions: PyArray2::from_owned_array(py, rest).unbind(),
            influence_joints: PyArray2::from_owned_array(py, joints).unbind(),
            influence_weights: PyArray2::from_owned_array(py, weights).unbind(),
            rows: (arrays.mesh_rows.into_iter())
                .map(|r| PyArray1::from_owned_array(py, Array1::from_vec(r)).unbind())
                .collect(),
            joint_names: arrays.joint_names,
            skinning: arrays.skinning,
            clip,
        })
    }
}

#[pymethods]
impl Frames {
    /// Each frame's time in seconds (float32, F).
    #[getter]
    fn times(&self, py: Python<'_>) -> Py<PyArray1<f32>> {
        self.times.clone_ref(py)
    }

    /// Skinned positions, model space (float32, F x V x 3).
    #[getter]
    fn positions(&self, py: Python<'_>) -> Py<PyArray3<f32>> {
        self.positions.clone_ref(py)
    }

    /// Joints' model-space matrices (float32, F x J x 4 x 4, row-major column-vector
    /// matrices: `M @ [x, y, z, 1]`).
    #[getter]
    fn joint_world(&self, py: Python<'_>) -> Py<PyArray4<f32>> {
        self.joint_world.clone_ref(py)
    }

    /// Skinning matrices: `joint_world` times each joint's inverse bind matrix (float32,
    /// F x J x 4 x 4).
    #[getter]
    fn skin_matrices(&self, py: Python<'_>) -> Py<PyArray4<f32>> {
        self.skin_matrices.clone_ref(py)
    }

    /// Rest positions (float32, V x 3).
    #[getter]
    fn rest_positions(&self, py: Python<'_>) -> Py<PyArray2<f32>> {
        self.rest_positions.clone_ref(py)
    }

    /// The influences skinned: (joints int32 V x K, weights float32 V x K), zero-padded.
    #[getter]
    fn influences(&self, py: Python<'_>) -> (Py<PyArray2<i32>>, Py<PyArray2<f32>>) {
        (
            self.influence_joints.clone_ref(py),
            self.influence_weights.clone_ref(py),
        )
    }

    /// Per mesh of the asset, per vertex of that mesh (`Mesh.positions`' rows): its row in
    /// `positions` (uint32). `positions[f][rows[m]]` is mesh `m` posed at frame `f`, to
    /// index with `Mesh.indices`.
    #[getter]
    fn rows(&self, py: Python<'_>) -> Vec<Py<PyArray1<u32>>> {
        self.rows.iter().map(|r| r.clone_ref(py)).collect()
    }

    fn __len__(&self, py: Python<'_>) -> usize {
        self.times.bind(py).len()
    }

    fn __repr__(&self, py: Python<'_>) -> String {
        let shape = self.positions.bind(py).shape().to_vec();
        format!(
            "<rigport.Frames {} frames, {} vertices, {} joints, {}>",
            shape[0],
            shape[1],
            self.joint_names.len(),
            self.skinning
        )
    }
}
