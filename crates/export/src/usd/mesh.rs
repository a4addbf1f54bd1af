//! Mesh prims: points, faces, normals, UVs, skinning primvars and BlendShape children.

use glam::{DMat4, Vec2, Vec3};
use rigport_model::{Asset, Mesh, Warning};

use super::skeleton::SKELETON;
use super::skin::{skin_rows, Binding};
use super::topology::{topology, Topology};
use super::values::{rows, zero, zeroed};
use super::{SkinningMethod, UsdOptions};
use crate::labels::mesh_label;
use rigport_usd::layer::{Specifier, Value};
use rigport_usd::sink::{AttrDecl, Data, Field, LayerSink, Targets};

/// One mesh as it will be written.
pub(super) struct MeshPlan {
    pub(super) prim: String,
    pub(super) binding: Binding,
    /// BlendShape prim names, one per morph target.
    pub(super) shapes: Vec<String>,
    /// The blend-shape channel tokens (unique over the stage), one per morph target.
    pub(super) channels: Vec<String>,
    /// The morph targets go out as `points.timeSamples` ([`super::UsdOptions::morphs_as_points`]).
    pub(super) points_cache: bool,
    /// The joint whose transform the Mesh prim carries as its own `xformOp`s (time-sampled
    /// from the first clip), instead of a rigid binding: a mesh attached to a root joint
    /// that nothing else uses (a USD source's animated static mesh, a glTF node animation).
    pub(super) xform_joint: Option<usize>,
}

/// What [`write_mesh`] needs besides the mesh.
pub(super) struct MeshContext<'a> {
    pub(super) root_path: &'a str,
    pub(super) skeleton_prims: &'a [String],
    pub(super) skeleton_binds: &'a [Vec<DMat4>],
    pub(super) options: &'a UsdOptions,
    /// Each material's prim path.
    pub(super) material_paths: &'a [String],
    /// The selected (first) clip and its `(time code, seconds)` samples, for point caches.
    pub(super) cache_clip: Option<(&'a rigport_model::Clip, &'a [(f64, f64)])>,
}

/// A primvar: `decl = value ( [elementSize = n] interpolation = "..." )`.
fn write_primvar(
    doc: &mut dyn LayerSink,
    decl: AttrDecl<'_>,
    value: Data<'_>,
    element_size: Option<usize>,
    interpolation: &str,
) {
    let mut meta = Vec::with_capacity(2);
    if let Some(n) = element_size {
        meta.push(Field::new("elementSize", (n as f64).into()));
    }
    meta.push(Field::new("interpolation", interpolation.into()));
    doc.attribute(decl, Some(value), &meta);
}

/// Points, normals or offsets as the sink takes them (`-0` as `0`).
fn float3s(values: &[Vec3]) -> Vec<[f32; 3]> {
    values.iter().map(|v| zeroed(v.to_array())).collect()
}

/// Writes one Mesh prim (and its BlendShape children).
pub(super) fn write_mesh(
    doc: &mut dyn LayerSink,
    asset: &Asset,
    mi: usize,
    mesh: &Mesh,
    plan: &MeshPlan,
    ctx: &MeshContext<'_>,
    warnings: &mut Vec<Warning>,
) {
    let label = mesh_label(mi, mesh);
    let material = mesh.material.and_then(|m| ctx.material_paths.get(m.get()));
    let mut schemas = Vec::new();
    if material.is_some() {
        schemas.push(Value::from("MaterialBindingAPI"));
    }
    if !matches!(plan.binding, Binding::None) {
        schemas.push(Value::from("SkelBindingAPI"));
    }
    // The source's name, when the prim's had to differ from it.
    let source_name = mesh_prim_source_name(mesh);
    let display = (!source_name.is_empty() && source_name != plan.prim).then_some(source_name);
    let mut meta = Vec::new();
    if !schemas.is_empty() {
        meta.push(Field::prepend("apiSchemas", Value::List(schemas)));
    }
    if let Some(name) = display {
        meta.push(Field::new("displayName", name.into()));
    }
    doc.begin_prim(Specifier::Def, Some("Mesh"), &plan.prim, &meta);

    if let Some((lo, hi)) = mesh.bounds() {
        doc.attribute(
            AttrDecl::new("float3[]", "extent"),
            Some(Data::Float3s(&float3s(&[lo, hi]))),
            &[],
        );
    }
    let skin = match plan.binding {
        Binding::Skinned { skin, .. } => asset.skins.get(skin),
        _ => None,
    };
    let topo = topology(mesh, skin);
    doc.attribute(
        AttrDecl::new("int[]", "faceVertexCounts"),
        Some(Data::Ints(&topo.counts)),
        &[],
    );
    // Faces are counter-clockwise (glTF's and the model's rule), USD's default
    // `orientation = "rightHanded"`: written as they are.
    let flat: Vec<u32> = topo
        .corners
        .iter()
        .map(|&v| topo.vertex_point[v as usize])
        .collect();
    doc.attribute(
        AttrDecl::new("int[]", "faceVertexIndices"),
        Some(Data::Ints(&flat)),
        &[],
    );

    let normals = float3s(&mesh_normals(mesh, &label, warnings));
    write_vertex_data(doc, AttrDecl::new("normal3f[]", "normals"), &topo, &normals);
    doc.attribute(
        AttrDecl::new("point3f[]", "points"),
        Some(Data::Float3s(&pick(
            &float3s(&mesh.positions),
            &topo.point_vertex,
        ))),
        &[],
    );
    if plan.points_cache {
        write_point_samples(doc, mi, mesh, ctx);
    }
    if let Some(joint) = plan.xform_joint {
        write_xform_ops(doc, asset, joint, ctx);
    }

    // The dump of `rigport eval` lists vertices by source vertex; say how points map to
    // them when the mesh split vertices (seams) that could not be merged back.
    let identity = topo.merged
        || mesh
            .source_vertex
            .iter()
            .enumerate()
            .all(|(v, &s)| s as usize == v);
    if !identity {
        write_primvar(
            doc,
            AttrDecl::new("int[]", "primvars:rigport:sourceVertex"),
            Data::Ints(&mesh.source_vertex),
            None,
            "vertex",
        );
    }

    let skeleton_path = |k: usize| {
        format!(
            "{}/{}",
            ctx.root_path,
            ctx.skeleton_prims.get(k).map_or(SKELETON, String::as_str)
        )
    };
    let mut skeleton_rel = None;
    match plan.binding {
        Binding::None => {}
        Binding::MorphOnly => skeleton_rel = Some(skeleton_path(0)),
        Binding::Rigid { joint } => {
            // Points are in the joint's space: geomBindTransform carries them to the
            // joint's bind pose, where the skinning transform (jointWorld · bind⁻¹) takes
            // over, so the mesh moves as jointWorld · p.
            let bind = ctx
                .skeleton_binds
                .first()
                .and_then(|b| b.get(joint))
                .copied()
                .unwrap_or(DMat4::IDENTITY);
            write_geom_bind(doc, &bind);
            write_primvar(
                doc,
                AttrDecl::new("int[]", "primvars:skel:jointIndices"),
                Data::Ints(&[joint as u32]),
                Some(1),
                "constant",
            );
            write_primvar(
                doc,
                AttrDecl::new("float[]", "primvars:skel:jointWeights"),
                Data::Floats(&[1.0]),
                Some(1),
                "constant",
            );
            skeleton_rel = Some(skeleton_path(0));
        }
        Binding::Skinned {
            skin,
            skeleton,
            geom_bind,
        } => {
            if let Some(binding) = asset.skins.get(skin) {
                let mut rows = skin_rows(asset, skin, binding, &label, warnings);
                if topo.merged {
                    let es = rows.element_size;
                    let row = |v: u32| (v as usize * es)..(v as usize + 1) * es;
                    rows.indices = topo
                        .point_vertex
                        .iter()
                        .flat_map(|&v| rows.indices.get(row(v)).unwrap_or_default().to_vec())
                        .collect();
                    rows.weights = topo
                        .point_vertex
                        .iter()
                        .flat_map(|&v| rows.weights.get(row(v)).unwrap_or_default().to_vec())
                        .collect();
                }
                write_geom_bind(doc, &geom_bind);
                let weights: Vec<f32> = rows.weights.iter().map(|&w| zero(w)).collect();
                write_primvar(
                    doc,
                    AttrDecl::new("int[]", "primvars:skel:jointIndices"),
                    Data::Ints(&rows.indices),
                    Some(rows.element_size),
                    "vertex",
                );
                write_primvar(
                    doc,
                    AttrDecl::new("float[]", "primvars:skel:jointWeights"),
                    Data::Floats(&weights),
                    Some(rows.element_size),
                    "vertex",
                );
                if ctx.options.skinning.unwrap_or(binding.method) == SkinningMethod::Dqs {
                    doc.attribute(
                        AttrDecl::uniform("token", "primvars:skel:skinningMethod"),
                        Some(Data::Str("dualQuaternion")),
                        &[],
                    );
                }
            }
            skeleton_rel = Some(skeleton_path(skeleton));
        }
    }

    if let Some(uvs) = &mesh.uvs {
        write_vertex_data(
            doc,
            AttrDecl::new("texCoord2f[]", "primvars:st"),
            &topo,
            &st(uvs),
        );
    }

    // Further UV sets: primvars:st1, st2, ... (same convention).
    for (k, uvs) in mesh.extra_uvs.iter().enumerate() {
        let name = format!("primvars:{}", super::material::st_name(k as u32 + 1));
        write_primvar(
            doc,
            AttrDecl::new("texCoord2f[]", &name),
            Data::Float2s(&st(uvs)),
            None,
            "vertex",
        );
    }
    if let Some(path) = material {
        doc.relationship("material:binding", Targets::One(path));
    }

    let mesh_path = format!("{}/{}", ctx.root_path, plan.prim);
    if !plan.channels.is_empty() && skeleton_rel.is_some() {
        let channels: Vec<&str> = plan.channels.iter().map(String::as_str).collect();
        doc.attribute(
            AttrDecl::uniform("token[]", "skel:blendShapes"),
            Some(Data::Strs(&channels)),
            &[],
        );
        let targets: Vec<String> = plan
            .shapes
            .iter()
            .map(|shape| format!("{mesh_path}/{shape}"))
            .collect();
        doc.relationship("skel:blendShapeTargets", Targets::List(&targets));
    }
    if let Some(path) = &skeleton_rel {
        doc.relationship("skel:skeleton", Targets::One(path));
    }
    // rigport meshes are polygonal; USD's fallback scheme would subdivide them.
    doc.attribute(
        AttrDecl::uniform("token", "subdivisionScheme"),
        Some(Data::Str("none")),
        &[],
    );

    if skeleton_rel.is_some() {
        for (target, shape) in mesh.morph_targets.iter().zip(&plan.shapes) {
            doc.blank_line();
            write_blend_shape(doc, target, shape, &topo.point_vertex);
        }
    }
    doc.end_prim();
}

/// A UV set as USD's `st`: the model's UVs follow glTF (origin top-left, v down); USD's st
/// have their origin bottom-left with t up.
fn st(uvs: &[Vec2]) -> Vec<[f32; 2]> {
    uvs.iter().map(|uv| zeroed([uv.x, 1.0 - uv.y])).collect()
}

/// The values of the vertices `which` (a point's vertex), in that order.
fn pick<T: Copy + Default>(values: &[T], which: &[u32]) -> Vec<T> {
    which
        .iter()
        .map(|&v| values.get(v as usize).copied().unwrap_or_default())
        .collect()
}

/// A per-vertex primvar: `vertex` interpolation when every point's vertices agree (bit for
/// bit), else `faceVarying`, one value per face corner.
fn write_vertex_data<T: Copy + Default + PartialEq>(
    doc: &mut dyn LayerSink,
    decl: AttrDecl<'_>,
    topo: &Topology,
    values: &[T],
) where
    for<'v> &'v [T]: Into<Data<'v>>,
{
    if topo.per_point(|a, b| values.get(a) == values.get(b)) {
        let per_point = pick(values, &topo.point_vertex);
        write_primvar(doc, decl, per_point.as_slice().into(), None, "vertex");
    } else {
        let per_corner = pick(values, &topo.corners);
        write_primvar(doc, decl, per_corner.as_slice().into(), None, "faceVarying");
    }
}

/// `point3f[] points.timeSamples`: at each time code of the selected clip, the rest points
/// plus the morph targets weighted by the clip's weight track of mesh `mi` (summed in
/// `f64` in target order, then rounded to `f32`). Nothing without such a track.
fn write_point_samples(doc: &mut dyn LayerSink, mi: usize, mesh: &Mesh, ctx: &MeshContext<'_>) {
    let Some((clip, times)) = ctx.cache_clip else {
        return;
    };
    let Some(track) = clip.tracks.iter().find(|t| {
        t.target == rigport_model::TrackTarget::MorphWeights(rigport_model::MeshIndex(mi as u32))
    }) else {
        return;
    };
    let k = mesh.morph_targets.len();
    if track.components() != k {
        return;
    }
    let sampler = super::sampler::Sampler::new(track);
    let mut weights = vec![0.0f64; k];
    let mut points: Vec<[f32; 3]> = Vec::with_capacity(mesh.positions.len());
    doc.begin_time_samples(AttrDecl::new("point3f[]", "points"));
    for &(tc, seconds) in times {
        sampler.sample(seconds, &mut weights);
        points.clear();
        for (v, rest) in mesh.positions.iter().enumerate() {
            let mut p = rest.as_dvec3();
            for (target, &w) in mesh.morph_targets.iter().zip(&weights) {
                if w != 0.0 {
                    if let Some(d) = target.position_deltas.get(v) {
                        p += d.as_dvec3() * w;
                    }
                }
            }
            points.push(zeroed(p.as_vec3().to_array()));
        }
        doc.time_sample(tc, Data::Float3s(&points));
    }
    doc.end_time_samples();
}

/// `matrix4d primvars:skel:geomBindTransform = ...`.
fn write_geom_bind(doc: &mut dyn LayerSink, m: &DMat4) {
    doc.attribute(
        AttrDecl::new("matrix4d", "primvars:skel:geomBindTransform"),
        Some(Data::Matrix4(rows(m))),
        &[],
    );
}

/// One BlendShape prim: offsets (sparse with `pointIndices` when some points do not move).
fn write_blend_shape(
    doc: &mut dyn LayerSink,
    target: &rigport_model::MorphTarget,
    prim: &str,
    point_vertex: &[u32],
) {
    let target = &rigport_model::MorphTarget {
        name: target.name.clone(),
        position_deltas: pick(&target.position_deltas, point_vertex),
        normal_deltas: target.normal_deltas.as_ref().map(|d| pick(d, point_vertex)),
    };
    let moved: Vec<usize> = (0..target.position_deltas.len())
        .filter(|&v| {
            target
                .position_deltas
                .get(v)
                .is_some_and(|d| *d != Vec3::ZERO)
                || target
                    .normal_deltas
                    .as_ref()
                    .and_then(|n| n.get(v))
                    .is_some_and(|d| *d != Vec3::ZERO)
        })
        .collect();
    let dense = moved.is_empty() || moved.len() == target.position_deltas.len();
    let pick = |values: &[Vec3]| -> Vec<Vec3> {
        if dense {
            values.to_vec()
        } else {
            moved
                .iter()
                .filter_map(|&v| values.get(v).copied())
                .collect()
        }
    };
    doc.begin_prim(Specifier::Def, Some("BlendShape"), prim, &[]);
    if let Some(normals) = &target.normal_deltas {
        doc.attribute(
            AttrDecl::uniform("vector3f[]", "normalOffsets"),
            Some(Data::Float3s(&float3s(&pick(normals)))),
            &[],
        );
    }
    doc.attribute(
        AttrDecl::uniform("vector3f[]", "offsets"),
        Some(Data::Float3s(&float3s(&pick(&target.position_deltas)))),
        &[],
    );
    if !dense {
        let moved: Vec<u32> = moved.iter().map(|&v| v as u32).collect();
        doc.attribute(
            AttrDecl::uniform("int[]", "pointIndices"),
            Some(Data::Ints(&moved)),
            &[],
        );
    }
    doc.end_prim();
}

/// Unit normals: given ones (already-unit kept bit for bit, others normalized, zero-length
/// ones replaced by computed ones with a warning), or computed from the triangles.
fn mesh_normals(mesh: &Mesh, label: &str, warnings: &mut Vec<Warning>) -> Vec<Vec3> {
    let Some(given) = &mesh.normals else {
        return mesh.compute_normals();
    };
    let mut computed: Option<Vec<Vec3>> = None;
    let mut repaired = 0;
    let out = given
        .iter()
        .enumerate()
        .map(|(v, n)| {
            if (n.length_squared() - 1.0).abs() <= 1e-6 {
                return *n;
            }
            n.try_normalize().unwrap_or_else(|| {
                repaired += 1;
                computed
                    .get_or_insert_with(|| mesh.compute_normals())
                    .get(v)
                    .copied()
                    .unwrap_or(Vec3::Y)
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

/// The name a mesh's prim is made from: its source node's, else its own.
pub(crate) fn mesh_prim_source_name(mesh: &rigport_model::Mesh) -> &str {
    if mesh.node_name.is_empty() {
        &mesh.name
    } else {
        &mesh.node_name
    }
}

/// `xformOp:translate`, `xformOp:orient` and `xformOp:scale` of a Mesh prim that carries
/// joint `joint`'s local transform: the rest value as default, and where the first clip
/// animates the joint, time samples at the clip's time codes (rotations unit and
/// sign-continuous; USD slerps `quatf` between samples as glTF LINEAR does).
fn write_xform_ops(doc: &mut dyn LayerSink, asset: &Asset, joint: usize, ctx: &MeshContext<'_>) {
    use rigport_model::{JointIndex, TrackTarget};
    let Some(rest) = asset.skeleton.joints().get(joint).map(|j| j.rest_local) else {
        return;
    };
    let j = JointIndex(joint as u32);
    let track = |target: TrackTarget| {
        ctx.cache_clip.and_then(|(clip, times)| {
            Some((clip.tracks.iter().find(|t| t.target == target)?, times))
        })
    };
    let unit = |q: [f64; 4]| {
        let n = q.iter().map(|c| c * c).sum::<f64>().sqrt();
        if n > 0.0 {
            q.map(|c| (c / n) as f32)
        } else {
            [0.0, 0.0, 0.0, 1.0]
        }
    };
    // (name, type, rest value as written, track, components)
    let r = rest.rotation.to_array();
    let ops: [(&str, &str, Vec<f32>, Option<_>); 3] = [
        (
            "xformOp:translate",
            "float3",
            rest.translation.to_array().to_vec(),
            track(TrackTarget::Translation(j)),
        ),
        (
            "xformOp:orient",
            "quatf",
            vec![r[3], r[0], r[1], r[2]],
            track(TrackTarget::Rotation(j)),
        ),
        (
            "xformOp:scale",
            "float3",
            rest.scale.to_array().to_vec(),
            track(TrackTarget::Scale(j)),
        ),
    ];
    for (name, ty, value, sampled) in ops {
        let decl = AttrDecl::new(ty, name);
        let tuple = |v: &[f32]| -> Data<'static> {
            match *v {
                [a, b, c] => Data::Float3(zeroed([a, b, c])),
                [a, b, c, d] => Data::Float4(zeroed([a, b, c, d])),
                _ => Data::Floats(&[]),
            }
        };
        doc.attribute(decl, Some(tuple(&value)), &[]);
        let Some((track, times)) = sampled else {
            continue;
        };
        let sampler = super::sampler::Sampler::new(track);
        let mut out = [0.0f64; 4];
        let mut prev: Option<[f32; 4]> = None;
        doc.begin_time_samples(decl);
        for &(tc, seconds) in times {
            sampler.sample(seconds, &mut out);
            let value: Vec<f32> = if name == "xformOp:orient" {
                let mut q = unit([out[0], out[1], out[2], out[3]]);
                if let Some(p) = prev {
                    if p.iter().zip(&q).map(|(a, b)| a * b).sum::<f32>() < 0.0 {
                        q = q.map(|c| -c);
                    }
                }
                prev = Some(q);
                vec![q[3], q[0], q[1], q[2]]
            } else {
                out[..3].iter().map(|&v| v as f32).collect()
            };
            doc.time_sample(tc, tuple(&value));
        }
        doc.end_time_samples();
    }
    doc.attribute(
        AttrDecl::uniform("token[]", "xformOpOrder"),
        Some(Data::Strs(&[
            "xformOp:translate",
            "xformOp:orient",
            "xformOp:scale",
        ])),
        &[],
    );
}
