//! Asset -> glTF JSON + binary buffer: nodes, meshes, skins (animations in `animation.rs`).

use std::collections::BTreeMap;

use glam::Vec3;
use gltf_json as json;
use json::accessor::Type;
use json::buffer::Target;
use json::mesh::{Mode, Semantic};
use json::validation::Checked;
use json::Index;
use rigport_model::quantize::PositionGrid;
use rigport_model::{Asset, Mesh, Skeleton, SkinBinding, Warning};

use super::animation;
use super::buffer::{Bounds, Builder};
use super::material::{self, ImagePlacement};
use super::unit_quat;
use super::weights::{self, SET_SLOTS};
use crate::labels::{fallback_palette_index, mesh_label};
use crate::{ExportError, GltfOptions};

/// Name of the node inserted above all skeleton roots when a skin's joints have no common
/// ancestor (see [`build`]).
pub(crate) const EXTRA_ROOT_NAME: &str = "rigport_root";

/// Largest deviation of an inverse bind matrix's last row from `(0, 0, 0, 1)` that is
/// treated as rounding noise. Inverting an affine `f32` matrix leaves errors around 1e-7;
/// anything larger is a projective component glTF cannot represent, and is reported.
const IBM_LAST_ROW_TOLERANCE: f32 = 1e-5;

/// The finished document (without its `buffers` entry) and its binary data.
pub(crate) struct Built {
    /// The JSON document; views refer to buffer 0, which the caller adds if `bin` is not
    /// empty.
    pub root: json::Root,
    /// The binary buffer, a multiple of 4 bytes long.
    pub bin: Vec<u8>,
    /// Lossy or repairing steps taken.
    pub warnings: Vec<Warning>,
    /// With [`rigport_model::Compression::Meshopt`]: the compressed views, which the
    /// caller declares ([`super::finish_json`]).
    pub compressed: Option<super::meshopt::Compressed>,
}

/// Builds the glTF document for `asset`.
///
/// Layout: node `i` is skeleton joint `i` (so joint indices are node indices), then the
/// optional [`EXTRA_ROOT_NAME`] node, then one node per mesh in mesh order.
///
/// `rigport_root` exists because glTF requires every skin's joints to share a common root
/// (validator: `SKIN_NO_COMMON_ROOT`), and `skin.skeleton`, when set, to be that root. A
/// skin whose palette spans several skeleton roots has none; an identity node above all the
/// roots provides one without changing any world transform.
///
/// # Errors
/// [`ExportError::MaxInfluences`] for a bad option, [`ExportError::Invalid`] with every
/// problem found in the asset.
pub(crate) fn build(
    asset: &Asset,
    opts: &GltfOptions,
    images: &ImagePlacement<'_>,
) -> Result<Built, ExportError> {
    if !(1..=weights::MAX_SLOTS).contains(&opts.max_influences) {
        return Err(ExportError::MaxInfluences {
            max_influences: opts.max_influences,
        });
    }
    let problems = crate::checks::check(asset, &crate::checks::GLTF);
    if !problems.is_empty() {
        return Err(ExportError::Invalid { problems });
    }
    // glTF is +Y up in metres: a source in another frame is converted (see `frame.rs`).
    let mut warnings = Vec::new();
    for (si, skin) in asset.skins.iter().enumerate() {
        if skin.method != rigport_model::SkinningMethod::Lbs {
            warnings.push(Warning::Repaired {
                location: format!("skin {si}"),
                message: "the source skins this mesh with dual quaternions; glTF skins \
                          linearly, so the file deforms differently (`rigport bake \
                          --skinning dqs` bakes the DQS result into morph targets)"
                    .into(),
            });
        }
    }
    // The grid's allowance is in the source's unit; the positions are quantized in metres.
    let position_error = opts.position_error * super::frame::length_scale(asset) as f32;
    let converted = super::frame::to_gltf_frame(asset, &mut warnings)?;
    let asset = converted.as_ref().unwrap_or(asset);

    let mut b = Builder::new(json::Asset {
        generator: Some(format!("rigport {}", env!("CARGO_PKG_VERSION"))),
        version: "2.0".into(),
        ..Default::default()
    });
    b.group_animation = opts.compact;
    if opts.compression == rigport_model::Compression::Meshopt {
        b.compressed = Some(super::meshopt::Compressed::default());
        b.filter_vectors = opts.compact;
        if opts.vector_bits == 16 {
            b.vector_bits = super::meshopt::EXP_BITS_SHORT;
        }
    }
    let skeleton = &asset.skeleton;
    let joint_count = skeleton.len();

    // Joint nodes, node index = joint index.
    let mut nodes: Vec<json::Node> = skeleton.joints().iter().map(joint_node).collect();
    let mut children: Vec<Vec<usize>> = vec![Vec::new(); joint_count];
    let mut skeleton_roots = Vec::new();
    for (i, joint) in skeleton.joints().iter().enumerate() {
        match joint.parent {
            Some(p) => children[p.get()].push(i),
            None => skeleton_roots.push(i),
        }
    }

    // Skin roots, and the extra root when some palette has no common ancestor.
    let skin_roots: Vec<Option<usize>> = asset
        .skins
        .iter()
        .map(|s| common_ancestor(skeleton, &s.joints))
        .collect();
    let mut scene_roots = Vec::new();
    let extra_root = if skin_roots.iter().any(Option::is_none) {
        let index = nodes.len();
        nodes.push(json::Node {
            name: Some(EXTRA_ROOT_NAME.into()),
            ..Default::default()
        });
        children.push(skeleton_roots.clone());
        scene_roots.push(index);
        Some(index)
    } else {
        scene_roots.extend_from_slice(&skeleton_roots);
        None
    };

    material::write_materials(&mut b, asset, images, &mut warnings);

    // Meshes and their nodes.
    let mut skin_of_mesh: BTreeMap<usize, usize> = BTreeMap::new();
    for (si, skin) in asset.skins.iter().enumerate() {
        skin_of_mesh.insert(skin.mesh.get(), si);
    }
    // A mesh that sat on a joint's own node in the source (`Mesh::node_name` is the joint's
    // name) goes back onto it, when it is the only one, so it keeps its node and name.
    let on_joint = |mi: usize, mesh: &Mesh| match (skin_of_mesh.contains_key(&mi), mesh.attached_to)
    {
        (false, Some(j)) => (mesh.node_name == skeleton.joint(j).name).then_some(j.get()),
        _ => None,
    };
    let mut on_joint_count = vec![0_usize; joint_count];
    for (mi, mesh) in asset.meshes.iter().enumerate() {
        if let Some(j) = on_joint(mi, mesh) {
            on_joint_count[j] += 1;
        }
    }
    // KHR_mesh_quantization: the grid of each skinned mesh without morph targets (its
    // skin's inverse bind matrices decode it).
    let grids: Vec<Option<PositionGrid>> = asset
        .meshes
        .iter()
        .enumerate()
        .map(|(mi, mesh)| {
            let quantized = opts.quantize_mesh
                && skin_of_mesh.contains_key(&mi)
                && mesh.morph_targets.is_empty();
            quantized
                .then(|| PositionGrid::within(&mesh.positions, position_error))
                .flatten()
        })
        .collect();
    if grids.iter().any(Option::is_some) {
        let name = "KHR_mesh_quantization".to_owned();
        b.root.extensions_used.push(name.clone());
        // "must be required": readers without it would read integers as floats.
        b.root.extensions_required.push(name);
    }
    let mut mesh_nodes = Vec::with_capacity(asset.meshes.len());
    for (mi, mesh) in asset.meshes.iter().enumerate() {
        let skin = skin_of_mesh.get(&mi).map(|&si| (si, &asset.skins[si]));
        let grid = grids[mi];
        let gltf_mesh = write_mesh(&mut b, asset, (mi, grid), mesh, skin, opts, &mut warnings)?;
        if let Some(j) = on_joint(mi, mesh).filter(|&j| on_joint_count[j] == 1) {
            nodes[j].mesh = Some(gltf_mesh);
            mesh_nodes.push(j);
            continue;
        }
        let node = nodes.len();
        // A skinned mesh's own node (at the scene root) keeps the source node's name.
        let node_name = if skin.is_none() || mesh.node_name.is_empty() {
            &mesh.name
        } else {
            &mesh.node_name
        };
        nodes.push(json::Node {
            name: non_empty(node_name),
            mesh: Some(gltf_mesh),
            skin: skin.map(|(si, _)| Index::new(si as u32)),
            ..Default::default()
        });
        children.push(Vec::new());
        // A skinned mesh is placed by its joints alone: at the scene root with no transform
        // (glTF 2.0 §3.7.3 "Skins"; validator NODE_SKINNED_MESH_NON_ROOT / _LOCAL_TRANSFORMS).
        match (skin, mesh.attached_to) {
            (None, Some(joint)) => children[joint.get()].push(node),
            _ => scene_roots.push(node),
        }
        mesh_nodes.push(node);
    }

    // Skins.
    for (si, skin) in asset.skins.iter().enumerate() {
        let skeleton_node = skin_roots[si].or(extra_root);
        let grid = grids.get(skin.mesh.get()).copied().flatten();
        write_skin(
            &mut b,
            asset,
            (si, grid),
            skin,
            skeleton_node,
            &mut warnings,
        );
    }

    animation::write_animations(&mut b, asset, &mesh_nodes, opts, &mut warnings);

    for (node, kids) in nodes.iter_mut().zip(children) {
        if !kids.is_empty() {
            node.children = Some(kids.into_iter().map(|k| Index::new(k as u32)).collect());
        }
    }
    b.root.nodes = nodes;
    b.root.scenes.push(json::Scene {
        extensions: None,
        extras: None,
        name: non_empty(&asset.name),
        nodes: scene_roots
            .into_iter()
            .map(|n| Index::new(n as u32))
            .collect(),
    });
    b.root.scene = Some(Index::new(0));

    let pad = b.bin.len().wrapping_neg() % 4;
    b.bin.resize(b.bin.len() + pad, 0);
    b.finish_groups();
    Ok(Built {
        root: b.root,
        bin: b.bin,
        warnings,
        compressed: b.compressed,
    })
}

/// `Some(name)` unless empty.
fn non_empty(name: &str) -> Option<String> {
    (!name.is_empty()).then(|| name.to_owned())
}

/// A joint's node: name and rest TRS, identity components omitted (they are the defaults).
fn joint_node(joint: &rigport_model::Joint) -> json::Node {
    let t = &joint.rest_local;
    // Checked non-degenerate in `check`; the validator requires unit length (ROTATION_NON_UNIT).
    let q = unit_quat(t.rotation.to_array());
    json::Node {
        name: Some(joint.name.clone()),
        translation: (t.translation != Vec3::ZERO).then(|| t.translation.to_array()),
        // (0, 0, 0, ±1) is the identity rotation.
        rotation: (q[..3] != [0.0; 3]).then_some(json::scene::UnitQuaternion(q)),
        scale: (t.scale != Vec3::ONE).then(|| t.scale.to_array()),
        ..Default::default()
    }
}

/// The nearest common ancestor of `joints` (a joint counts as its own ancestor), or `None`
/// when they lie under different roots or the list is empty.
pub(crate) fn common_ancestor(
    skeleton: &Skeleton,
    joints: &[rigport_model::JointIndex],
) -> Option<usize> {
    let parents: Vec<Option<usize>> = skeleton.parents().map(|p| p.map(|p| p.get())).collect();
    // Parents come first, so depths are one pass.
    let mut depth = vec![0_usize; parents.len()];
    for i in 0..parents.len() {
        if let Some(p) = parents[i] {
            depth[i] = depth[p] + 1;
        }
    }
    let mut iter = joints.iter().map(|j| j.get());
    let mut acc = iter.next()?;
    for mut other in iter {
        let mut a = acc;
        while depth[a] > depth[other] {
            a = parents[a]?;
        }
        while depth[other] > depth[a] {
            other = parents[other]?;
        }
        while a != other {
            a = parents[a]?;
            other = parents[other]?;
        }
        acc = a;
    }
    Some(acc)
}

/// `1 vertex`, `2 vertices`.
fn vertices(n: usize) -> String {
    format!("{n} {}", if n == 1 { "vertex" } else { "vertices" })
}

/// Flattens vectors to floats.
fn flat3(v: &[Vec3]) -> Vec<f32> {
    v.iter().flat_map(|p| p.to_array()).collect()
}

/// Writes one mesh as a glTF mesh with one primitive; returns its index.
fn write_mesh(
    b: &mut Builder,
    asset: &Asset,
    (mi, grid): (usize, Option<PositionGrid>),
    mesh: &Mesh,
    skin: Option<(usize, &SkinBinding)>,
    opts: &GltfOptions,
    warnings: &mut Vec<Warning>,
) -> Result<Index<json::Mesh>, ExportError> {
    let label = mesh_label(mi, mesh);
    let mut attributes = BTreeMap::new();
    let array = Some(Target::ArrayBuffer);

    let positions = match grid {
        Some(grid) => {
            let q: Vec<[i16; 3]> = mesh.positions.iter().map(|&p| grid.encode(p)).collect();
            b.padded_vec3_i16(&q, false, Bounds::MinMax)
        }
        None => b.floats(&flat3(&mesh.positions), Type::Vec3, array, Bounds::MinMax),
    };
    attributes.insert(Checked::Valid(Semantic::Positions), positions);

    // Normals must be unit length (validator ACCESSOR_VECTOR3_NON_UNIT).
    let normals = match &mesh.normals {
        None => mesh.compute_normals(),
        Some(given) => {
            let mut computed: Option<Vec<Vec3>> = None;
            let mut repaired = 0;
            let out = given
                .iter()
                .enumerate()
                .map(|(v, n)| {
                    // Already-unit normals are kept bit for bit, so re-exporting a file
                    // reproduces it (the validator allows 0.00005; 1e-6 is far inside).
                    if (n.length_squared() - 1.0).abs() <= 1e-6 {
                        return *n;
                    }
                    n.try_normalize().unwrap_or_else(|| {
                        repaired += 1;
                        computed.get_or_insert_with(|| mesh.compute_normals())[v]
                    })
                })
                .collect();
            if repaired > 0 {
                warnings.push(Warning::Repaired {
                    location: format!("mesh {label:?}"),
                    message: format!(
                        "{repaired} zero-length normal{} replaced by computed ones",
                        if repaired == 1 { "" } else { "s" }
                    ),
                });
            }
            out
        }
    };
    let normals = if grid.is_some() {
        // 8-bit normalized (KHR_mesh_quantization), as gltfpack writes them: shading only.
        let unit: Vec<[f32; 3]> = normals.iter().map(|n| n.to_array()).collect();
        b.normals_i8(&unit)
    } else {
        b.floats(&flat3(&normals), Type::Vec3, array, Bounds::None)
    };
    attributes.insert(Checked::Valid(Semantic::Normals), normals);

    let mut uv_sets = 0;
    if let Some(uvs) = &mesh.uvs {
        for set in std::iter::once(uvs).chain(&mesh.extra_uvs) {
            let flat: Vec<f32> = set.iter().flat_map(|t| t.to_array()).collect();
            let acc = b.floats(&flat, Type::Vec2, array, Bounds::None);
            attributes.insert(Checked::Valid(Semantic::TexCoords(uv_sets)), acc);
            uv_sets += 1;
        }
    }
    // A texture read with a UV set the mesh lacks is an error (validator
    // MESH_PRIMITIVE_TOO_FEW_TEXCOORDS): such a mesh is written without its material.
    let material = mesh.material.filter(|m| {
        let needed = asset
            .materials
            .get(m.get())
            .map_or(0, material::uv_sets_needed);
        let ok = needed <= uv_sets;
        if !ok {
            warnings.push(Warning::Repaired {
                location: format!("mesh {label:?}"),
                message: format!(
                    "its {m} reads UV set {} but the mesh has {uv_sets}; written without \
                     the material",
                    needed - 1
                ),
            });
        }
        ok
    });

    if let Some((si, skin)) = skin {
        let fallback = fallback_palette_index(&asset.skeleton, &skin.joints);
        // Palette size <= 65536 is checked in `check`.
        let packed = weights::pack(&skin.influences, opts.max_influences, fallback as u16);
        let sets = if packed.uses_second_set() { 2 } else { 1 };
        for set in 0..sets {
            let slots = set * SET_SLOTS..(set + 1) * SET_SLOTS;
            let joints: Vec<u16> = packed
                .rows
                .iter()
                .flat_map(|r| r.joints[slots.clone()].to_vec())
                .collect();
            // JOINTS_n: UNSIGNED_BYTE when every palette index fits, else UNSIGNED_SHORT.
            let joints_acc = if skin.joints.len() <= 256 {
                let small: Vec<u8> = joints.iter().map(|&j| j as u8).collect();
                b.ints(&small, Type::Vec4, array)
            } else {
                b.ints(&joints, Type::Vec4, array)
            };
            let weights: Vec<f32> = packed
                .rows
                .iter()
                .flat_map(|r| r.weights[slots.clone()].to_vec())
                .collect();
            // Normalized bytes when that is exact (glTF 2.0 §3.7.3.3 allows them for weights).
            let exact_bytes = opts.compact
                && weights
                    .iter()
                    .all(|&w| (w * 255.0).round() / 255.0 == w && (0.0..=1.0).contains(&w));
            let weights_acc = if exact_bytes {
                let bytes: Vec<u8> = weights.iter().map(|&w| (w * 255.0).round() as u8).collect();
                b.normalized_u8(&bytes, Type::Vec4, array)
            } else {
                b.floats(&weights, Type::Vec4, array, Bounds::None)
            };
            attributes.insert(Checked::Valid(Semantic::Joints(set as u32)), joints_acc);
            attributes.insert(Checked::Valid(Semantic::Weights(set as u32)), weights_acc);
        }
        let s = packed.stats;
        if s.limited_vertices > 0 {
            warnings.push(Warning::InfluencesDropped {
                mesh: label.clone(),
                max_influences: opts.max_influences,
                vertices: s.limited_vertices,
                max_dropped_weight: s.max_dropped_weight,
            });
        }
        if s.renormalized_rows > 0 {
            warnings.push(Warning::WeightsRenormalized {
                source: format!("mesh {label:?} (skin {si})"),
                rows: s.renormalized_rows,
                max_row_sum_error: s.max_row_sum_error,
            });
        }
        if s.unbound_vertices > 0 {
            let root = asset.skeleton.joint(skin.joints[fallback]);
            warnings.push(Warning::Repaired {
                location: format!("mesh {label:?} (skin {si})"),
                message: format!(
                    "{} had no influence; bound with weight 1 to the skin's root joint {:?}",
                    vertices(s.unbound_vertices),
                    root.name
                ),
            });
        }
    }

    // Indices: UNSIGNED_SHORT while every index stays below 65535, the primitive restart
    // value that the validator rejects (ACCESSOR_INDEX_PRIMITIVE_RESTART).
    let flat: Vec<u32> = mesh.triangles.iter().flatten().copied().collect();
    let element = Some(Target::ElementArrayBuffer);
    let indices = if mesh.vertex_count() <= usize::from(u16::MAX) {
        let small: Vec<u16> = flat.iter().map(|&i| i as u16).collect();
        b.ints(&small, Type::Scalar, element)
    } else {
        b.ints(&flat, Type::Scalar, element)
    };

    // Morph targets. If any target has normal deltas, every target gets a NORMAL accessor
    // (zeros where absent) so all targets carry the same attributes.
    let with_normals = mesh.morph_targets.iter().any(|t| t.normal_deltas.is_some());
    let mut targets = Vec::with_capacity(mesh.morph_targets.len());
    for target in &mesh.morph_targets {
        // glTF 2.0 §3.7.2.2: POSITION targets require min/max. Targets that move under a
        // third of the vertices (baked correctives, most blend shapes) are written as sparse
        // accessors (§3.6.2.3): 16 bytes per moved vertex instead of 12 per vertex.
        let flat = flat3(&target.position_deltas);
        let moved = target
            .position_deltas
            .iter()
            .filter(|d| **d != Vec3::ZERO)
            .count();
        let positions = if moved * 3 < target.position_deltas.len() {
            b.sparse_floats(&flat, Type::Vec3)
        } else {
            b.floats(&flat, Type::Vec3, array, Bounds::MinMax)
        };
        let normals = with_normals.then(|| {
            let flat = match &target.normal_deltas {
                Some(d) => flat3(d),
                None => vec![0.0; 3 * mesh.vertex_count()],
            };
            b.floats(&flat, Type::Vec3, array, Bounds::None)
        });
        targets.push(json::mesh::MorphTarget {
            positions: Some(positions),
            normals,
            tangents: None,
        });
    }

    let (weights, extras) = if mesh.morph_targets.is_empty() {
        (None, None)
    } else {
        let weights = if mesh.morph_weights.is_empty() {
            vec![0.0; mesh.morph_targets.len()]
        } else {
            mesh.morph_weights.clone()
        };
        // The de facto convention for target names (Blender, three.js, Babylon.js).
        let names: Vec<&str> = mesh.morph_targets.iter().map(|t| t.name.as_str()).collect();
        let text = serde_json::to_string(&serde_json::json!({ "targetNames": names }))?;
        (
            Some(weights),
            Some(json::extras::RawValue::from_string(text)?),
        )
    };

    let primitive = json::mesh::Primitive {
        attributes,
        extensions: None,
        extras: None,
        indices: Some(indices),
        material: material.map(|m| Index::new(m.0)),
        mode: Checked::Valid(Mode::Triangles),
        targets: (!targets.is_empty()).then_some(targets),
    };
    Ok(b.root.push(json::Mesh {
        extensions: None,
        extras,
        name: non_empty(&mesh.name),
        primitives: vec![primitive],
        weights,
    }))
}

/// Writes skin `si`: palette nodes, inverse bind matrices, skeleton root.
fn write_skin(
    b: &mut Builder,
    asset: &Asset,
    (si, grid): (usize, Option<PositionGrid>),
    skin: &SkinBinding,
    skeleton_node: Option<usize>,
    warnings: &mut Vec<Warning>,
) {
    let mut projective = 0;
    let mut ibm = Vec::with_capacity(16 * skin.inv_bind.len());
    // Quantized positions decode as `origin + step * q`: that map goes first.
    // (Without a grid the matrices are written as they are: multiplying by the identity
    // would turn their -0.0 into 0.0 and change the bytes of every plain file.)
    let decode = grid.map(|g| {
        glam::Mat4::from_translation(g.origin) * glam::Mat4::from_scale(glam::Vec3::splat(g.step))
    });
    for m in &skin.inv_bind {
        let m = &decode.map_or(*m, |d| *m * d);
        // Column-major: elements 3, 7, 11, 15 are the last row. glTF requires it to be
        // exactly (0, 0, 0, 1) (validator ACCESSOR_INVALID_IBM); force it.
        let mut cols = m.to_cols_array();
        let dev = [cols[3], cols[7], cols[11], cols[15] - 1.0]
            .iter()
            .fold(0.0_f32, |a, d| a.max(d.abs()));
        if dev > IBM_LAST_ROW_TOLERANCE {
            projective += 1;
        }
        cols[3] = 0.0;
        cols[7] = 0.0;
        cols[11] = 0.0;
        cols[15] = 1.0;
        ibm.extend_from_slice(&cols);
    }
    let mesh = &asset.meshes[skin.mesh.get()];
    if projective > 0 {
        warnings.push(Warning::Repaired {
            location: format!("skin {si} (mesh {:?})", mesh_label(skin.mesh.get(), mesh)),
            message: format!(
                "{projective} inverse bind matrices had a last row other than (0, 0, 0, 1); forced to it"
            ),
        });
    }
    let ibm = b.floats(&ibm, Type::Mat4, None, Bounds::None);
    b.root.push(json::Skin {
        extensions: None,
        extras: None,
        inverse_bind_matrices: Some(ibm),
        joints: skin.joints.iter().map(|j| Index::new(j.0)).collect(),
        name: non_empty(&mesh.name),
        skeleton: skeleton_node.map(|n| Index::new(n as u32)),
    });
}
