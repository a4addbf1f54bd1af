//! The procedural character in Pinocchio's layout: [`character`] runs the steps the crate
//! documentation lists (skeleton, body field, surface nets, weights).

use glam::Vec3;
use rigport_model::Mesh;

use crate::body::Body;
use crate::skeleton::skeleton;
use crate::surface_nets::{snap_to_surface, surface_nets};
use crate::weights::skin_weights;

/// The demo character's raw data, in Pinocchio's layout.
///
/// Model space, metres, +Y up, facing +Z, left = +X. Sizes: `J` joints, `J - 1` bones, `V`
/// vertices; bone `k - 1` (a weight column) runs from `joint_parents[k]` to joint `k`, rotates
/// about its head (the parent joint) and is independent of bones sharing its parent.
#[derive(Clone, Debug, PartialEq)]
pub struct DemoRig {
    /// The body: `V` positions, `V` unit normals, counter-clockwise triangles, no UVs,
    /// `source_vertex` the identity, name `"demo"`.
    pub mesh: Mesh,
    /// `J` joint positions, model space (Pinocchio's `skeleton.out`).
    pub joint_positions: Vec<Vec3>,
    /// `J` parents; joint 0 (`"hips"`) is the root, every parent comes before its children.
    pub joint_parents: Vec<Option<usize>>,
    /// `J` joint names (`"hips"`, `"spine"`, ..., `"toe_r"`), unique; `_l` is +X.
    pub joint_names: Vec<String>,
    /// `V` rows of `J - 1` weights (Pinocchio's `attachment.out`): column `k - 1` is the bone
    /// ending at joint `k`. Every weight is finite and `>= 0`, at most 4 per row are non-zero
    /// and every row sums to 1 (within 1e-6 in `f32`).
    pub bone_weights: Vec<Vec<f32>>,
}

/// The largest useful `detail` for [`character`]; larger values are clamped to it.
///
/// The vertex count grows as `detail²`: 8 gives about 680 000 vertices (some 7 s, 250 MB).
pub const MAX_DETAIL: u32 = 8;

/// Grid cell edge length at detail 1, metres. Chosen so that detail 1 has about 10 000
/// vertices, the narrowest gap that must stay open (between the knees, about 8 cm) is 5 cells
/// wide and the thinnest part (the thumb, about 3 cm) 2 cells thick.
const BASE_CELL: f32 = 0.015;

/// Builds the demo character.
///
/// `detail` sets the grid resolution: cell size `15 mm / detail`. 1 is the default (about
/// 10 000 vertices and 20 000 triangles, 20 to 30 ms in a release build); 0 is treated as 1
/// and values above [`MAX_DETAIL`] as [`MAX_DETAIL`]. The result depends on nothing but
/// `detail`: two calls return equal rigs, on any machine.
pub fn character(detail: u32) -> DemoRig {
    let detail = detail.clamp(1, MAX_DETAIL);
    let cell = BASE_CELL / detail as f32;
    let (joint_positions, joint_parents, joint_names) = skeleton();
    let body = Body::new(cell);
    let (mut positions, triangles) = surface_nets(&body);
    let normals = snap_to_surface(&body, &mut positions);
    let bone_weights = skin_weights(&joint_positions, &joint_parents, &joint_names, &positions);
    let source_vertex = (0..positions.len() as u32).collect();
    DemoRig {
        mesh: Mesh {
            name: "demo".to_owned(),
            positions,
            normals: Some(normals),
            triangles,
            source_vertex,
            ..Mesh::default()
        },
        joint_positions,
        joint_parents,
        joint_names,
        bone_weights,
    }
}

#[cfg(test)]
mod tests;
