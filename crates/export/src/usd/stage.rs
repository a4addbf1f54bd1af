//! Asset -> a USD stage: the layout (the root prim, a SkelRoot when skinned, the Skeleton
//! prims, the Animations scope, the clip variant set and the Mesh prims), described to a
//! `rigport-usd` [`LayerSink`] by [`build`] (the printer for `.usda`, the layer builder
//! for `.usdc`/`.usdz`).
//!
//! The parts live beside it: `checks` (what cannot be exported), `skeleton` (joint
//! tokens, bind poses), `skin` (bindings, influence primvars), `mesh` (Mesh and
//! BlendShape prims) and `anim` (SkelAnimation, frame rate, time codes).
//!
//! See the module docs of [`super`] for what is written and why.

use std::collections::BTreeMap;

use glam::DMat4;
use rigport_model::{Asset, Warning};
use rigport_usd::layer::{Specifier, Value};
use rigport_usd::sink::{AttrDecl, Data, Field, LayerSink, Targets};

use super::anim::{frame_rate, plan_clip, sample_times, write_animation, AnimPlan};
use super::material::{material_prims, write_materials, MATERIALS};
use super::mesh::{write_mesh, MeshContext, MeshPlan};
use super::names::{Namespace, Renames};
use super::skeleton::{bind_poses, joint_tokens, transform_d, SKELETON};
use super::skin::Binding;
use super::values::rows;
use super::UsdOptions;
use crate::checks::{check, USD};
use crate::{ExportError, Problem};

/// Name of the Scope holding the SkelAnimation prims.
pub(crate) const ANIMATIONS: &str = "Animations";
/// Name of the variant set choosing the clip bound to the skeleton.
pub(crate) const CLIP_VARIANT_SET: &str = "clip";
/// Time stamps per second when the first clip's keys fit no frame rate: milliseconds.
const FALLBACK_TIME_CODES_PER_SECOND: f64 = 1000.0;
/// Time stamps per second when there is nothing to measure (USD's own default).
const DEFAULT_TIME_CODES_PER_SECOND: f64 = 24.0;
/// Sampling rate for cubic-spline and step tracks when the keys fit no frame rate.
const FALLBACK_RESAMPLE_FPS: f64 = 30.0;

/// Describes the stage of `asset` to `doc`; returns the warnings of lossy steps.
///
/// # Errors
/// [`ExportError::Invalid`] listing every problem of the asset.
pub(crate) fn build(
    asset: &Asset,
    options: &UsdOptions,
    image_files: &[String],
    doc: &mut dyn LayerSink,
) -> Result<Vec<Warning>, ExportError> {
    let problems = check(asset, &USD);
    if !problems.is_empty() {
        return Err(ExportError::Invalid { problems });
    }
    let mut warnings = Vec::new();
    let skeleton = &asset.skeleton;
    let joint_count = skeleton.len();
    let skinned: std::collections::BTreeSet<usize> =
        asset.skins.iter().map(|s| s.mesh.get()).collect();
    let is_cache = |mi: usize, m: &rigport_model::Mesh| {
        options.morphs_as_points
            && !skinned.contains(&mi)
            && m.attached_to.is_none()
            && !m.morph_targets.is_empty()
    };
    let has_morphs = asset
        .meshes
        .iter()
        .enumerate()
        .any(|(mi, m)| !m.morph_targets.is_empty() && !is_cache(mi, m));
    // UsdSkel is needed for joints, and for blend shapes (which UsdSkel animates); an
    // asset with neither is plain geometry under an Xform.
    let skel_root = joint_count > 0 || has_morphs;

    // Joint path tokens: each name an identifier, unique among its siblings.
    let (joint_tokens, joint_renames) = joint_tokens(asset);
    if !joint_renames.is_empty() {
        warnings.push(Warning::Repaired {
            location: "skeleton".into(),
            message: joint_renames.message("joint"),
        });
    }

    // Rest matrices in f64: local, then model space (parents first).
    let rest_local: Vec<DMat4> = skeleton
        .joints()
        .iter()
        .map(|j| transform_d(&j.rest_local))
        .collect();
    let mut rest_model: Vec<DMat4> = Vec::with_capacity(joint_count);
    for (i, joint) in skeleton.joints().iter().enumerate() {
        let parent = joint.parent.and_then(|p| rest_model.get(p.get())).copied();
        rest_model.push(parent.unwrap_or(DMat4::IDENTITY) * rest_local[i]);
    }

    // Bind poses: one per Skeleton prim; skins placed on them.
    let (skeleton_binds, skin_places) = bind_poses(asset, &rest_model, &mut warnings);

    // Prim names below the root.
    let mut root_ns = Namespace::default();
    root_ns.reserve(ANIMATIONS);
    if !asset.materials.is_empty() {
        root_ns.reserve(MATERIALS);
    }
    let skeleton_prims: Vec<String> = (0..skeleton_binds.len())
        .map(|k| {
            let name = if k == 0 {
                SKELETON.to_owned()
            } else {
                format!("{SKELETON}_{k}")
            };
            root_ns.reserve(&name);
            name
        })
        .collect();

    let mut skin_of_mesh: BTreeMap<usize, usize> = BTreeMap::new();
    for (si, skin) in asset.skins.iter().enumerate() {
        skin_of_mesh.entry(skin.mesh.get()).or_insert(si);
    }
    let xform_joints = xform_joints(asset);
    let mut mesh_renames = Renames::default();
    let mut channel_ns = Namespace::default();
    let mut plans = Vec::with_capacity(asset.meshes.len());
    for (mi, mesh) in asset.meshes.iter().enumerate() {
        // The prim takes the name of the source node that held the mesh, when known.
        let name = super::mesh::mesh_prim_source_name(mesh);
        let (prim, renamed) = root_ns.claim(name, "mesh");
        if renamed && !name.is_empty() {
            mesh_renames.push(name, &prim);
        }
        let points_cache = is_cache(mi, mesh);
        let binding = match (skin_of_mesh.get(&mi), mesh.attached_to) {
            (Some(&si), _) => {
                let (skeleton, geom_bind) =
                    skin_places.get(si).copied().unwrap_or((0, DMat4::IDENTITY));
                Binding::Skinned {
                    skin: si,
                    skeleton,
                    geom_bind,
                }
            }
            (None, Some(j)) if xform_joints.contains(&j.get()) && mesh.morph_targets.is_empty() => {
                Binding::None
            }
            (None, Some(j)) => Binding::Rigid { joint: j.get() },
            (None, None) if points_cache => Binding::None,
            (None, None) if skel_root && !mesh.morph_targets.is_empty() => Binding::MorphOnly,
            (None, None) => Binding::None,
        };
        let mut shape_ns = Namespace::default();
        let mut shapes = Vec::new();
        let mut channels = Vec::new();
        for target in mesh.morph_targets.iter().filter(|_| !points_cache) {
            let (shape, renamed) = shape_ns.claim(&target.name, "shape");
            if renamed && !target.name.is_empty() {
                mesh_renames.push(&target.name, &shape);
            }
            // The channel is the shape's own name (so names survive a round trip), made
            // unique across the skeleton's meshes with the mesh's name on a clash.
            let wanted = if channel_ns.is_taken(&shape) {
                format!("{prim}_{shape}")
            } else {
                shape.clone()
            };
            let (channel, _) = channel_ns.claim(&wanted, "shape");
            shapes.push(shape);
            channels.push(channel);
        }
        let xform_joint = match (&binding, mesh.attached_to) {
            (Binding::None, Some(j)) => Some(j.get()),
            _ => None,
        };
        plans.push(MeshPlan {
            prim,
            xform_joint,
            binding,
            shapes,
            channels,
            points_cache,
        });
    }
    if !mesh_renames.is_empty() {
        warnings.push(Warning::Repaired {
            location: "meshes".into(),
            message: mesh_renames.message("mesh or morph target"),
        });
    }

    // Animations.
    let mut anims = Vec::new();
    if skel_root {
        let mut anim_ns = Namespace::default();
        let mut clip_renames = Renames::default();
        for clip in &asset.clips {
            let (prim, renamed) = anim_ns.claim(&clip.name, "clip");
            if renamed && !clip.name.is_empty() {
                clip_renames.push(&clip.name, &prim);
            }
            anims.push(plan_clip(asset, clip, prim, &plans, &mut warnings));
        }
        if !clip_renames.is_empty() {
            warnings.push(Warning::Repaired {
                location: "clips".into(),
                message: clip_renames.message("clip"),
            });
        }
    } else {
        for clip in &asset.clips {
            warnings.push(Warning::Repaired {
                location: format!("clip {:?}", clip.name),
                message:
                    "clip not written: the asset has no joints and no morph targets to animate"
                        .into(),
            });
        }
    }
    // Without clips, non-zero default morph weights still need an animation to take
    // effect (UsdSkel reads blend-shape weights only from the bound SkelAnimation).
    let rest_anim = anims.is_empty()
        && plans
            .iter()
            .zip(&asset.meshes)
            .any(|(p, m)| !p.channels.is_empty() && m.morph_weights.iter().any(|&w| w != 0.0));

    // Time codes: the first clip's frame rate, all clips sampled at seconds × rate.
    let detected_rate = anims.first().and_then(|a| frame_rate(&a.key_times));
    let tcps = match (detected_rate, anims.first()) {
        (Some(r), _) => r,
        (None, Some(a)) if a.key_times.len() >= 2 => FALLBACK_TIME_CODES_PER_SECOND,
        _ => DEFAULT_TIME_CODES_PER_SECOND,
    };
    let resample_fps = detected_rate.unwrap_or(FALLBACK_RESAMPLE_FPS);

    // USD wants a positive unit; 1 (metres) when the source does not say, as for glTF.
    let source_mpu = match asset.meters_per_unit {
        Some(m) if m.is_finite() && m > 0.0 => m,
        Some(m) => {
            warnings.push(Warning::Repaired {
                location: "asset".into(),
                message: format!("meters per unit {m} is not a positive number; wrote 1"),
            });
            1.0
        }
        None => 1.0,
    };
    // The stage's frame: the source's unless asked; the root prim's transform places the
    // model space in it.
    let up_axis = options.up_axis.unwrap_or(asset.frame.up_axis);
    let meters_per_unit = match options.meters_per_unit {
        Some(m) if m.is_finite() && m > 0.0 => m,
        Some(m) => {
            return Err(ExportError::Invalid {
                problems: vec![Problem::Asset(rigport_model::AssetError::NonFinite {
                    what: format!("the requested metersPerUnit {m}"),
                })],
            })
        }
        None => source_mpu,
    };
    let root_xform = asset
        .frame
        .model_to(Some(source_mpu), up_axis, Some(meters_per_unit));

    let root_name = {
        let mut ns = Namespace::default();
        ns.claim(&asset.name, "rig").0
    };
    let root_path = format!("/{root_name}");

    // The stage, described to the sink.
    let sampled: Vec<Vec<(f64, f64)>> = anims
        .iter()
        .map(|anim| sample_times(anim, tcps, resample_fps, &mut warnings))
        .collect();
    // Each clip's own range (its variant's); the stage's is the selected (first) clip's.
    let ranges: Vec<(f64, f64)> = sampled
        .iter()
        .map(|t| {
            let codes = t.iter().map(|&(tc, _)| tc);
            (
                codes.clone().fold(f64::INFINITY, f64::min),
                codes.fold(f64::NEG_INFINITY, f64::max),
            )
        })
        .map(|(a, b)| if a.is_finite() { (a, b) } else { (0.0, 0.0) })
        .collect();
    let (start, end) = ranges.first().copied().unwrap_or((0.0, 0.0));

    let mut layer_meta = vec![
        Field::new("defaultPrim", root_name.as_str().into()),
        Field::new(
            "doc",
            Value::Str(format!("Written by rigport {}", env!("CARGO_PKG_VERSION"))),
        ),
    ];
    if !anims.is_empty() || rest_anim {
        let (start, end) = if start.is_finite() {
            (start, end)
        } else {
            (0.0, 0.0)
        };
        layer_meta.extend([
            Field::new("endTimeCode", end.into()),
            Field::new("metersPerUnit", meters_per_unit.into()),
            Field::new("startTimeCode", start.into()),
            Field::new("timeCodesPerSecond", tcps.into()),
        ]);
    } else {
        layer_meta.push(Field::new("metersPerUnit", meters_per_unit.into()));
    }
    layer_meta.push(Field::new("upAxis", up_axis.as_str().into()));
    doc.begin_layer(&layer_meta);

    let root_type = if skel_root { "SkelRoot" } else { "Xform" };
    let root_meta = match anims.first() {
        Some(first) => vec![
            Field::new(
                "variants",
                Value::Dict(vec![(CLIP_VARIANT_SET.into(), first.prim.as_str().into())]),
            ),
            Field::prepend("variantSets", CLIP_VARIANT_SET.into()),
        ],
        None => Vec::new(),
    };
    doc.begin_prim(Specifier::Def, Some(root_type), &root_name, &root_meta);
    if root_xform != DMat4::IDENTITY {
        doc.attribute(
            AttrDecl::new("matrix4d", "xformOp:transform"),
            Some(Data::Matrix4(rows(&root_xform))),
            &[],
        );
        doc.attribute(
            AttrDecl::uniform("token[]", "xformOpOrder"),
            Some(Data::Strs(&["xformOp:transform"])),
            &[],
        );
        doc.blank_line();
    }

    if skel_root {
        let rest_anim_prim = "rest";
        let rest_anim_path = format!("{root_path}/{ANIMATIONS}/{rest_anim_prim}");
        let tokens: Vec<&str> = joint_tokens.iter().map(String::as_str).collect();
        let rest_rows: Vec<[f64; 16]> = rest_local.iter().map(rows).collect();
        for (k, prim) in skeleton_prims.iter().enumerate() {
            doc.begin_prim(
                Specifier::Def,
                Some("Skeleton"),
                prim,
                &[Field::prepend(
                    "apiSchemas",
                    Value::List(vec!["SkelBindingAPI".into()]),
                )],
            );
            let binds: Vec<[f64; 16]> = skeleton_binds
                .get(k)
                .map(|b| b.iter().map(rows).collect())
                .unwrap_or_default();
            doc.attribute(
                AttrDecl::uniform("matrix4d[]", "bindTransforms"),
                Some(Data::Matrix4s(&binds)),
                &[],
            );
            doc.attribute(
                AttrDecl::uniform("token[]", "joints"),
                Some(Data::Strs(&tokens)),
                &[],
            );
            doc.attribute(
                AttrDecl::uniform("matrix4d[]", "restTransforms"),
                Some(Data::Matrix4s(&rest_rows)),
                &[],
            );
            if rest_anim {
                doc.relationship("skel:animationSource", Targets::One(&rest_anim_path));
            }
            doc.end_prim();
            doc.blank_line();
        }

        if !anims.is_empty() || rest_anim {
            doc.begin_prim(Specifier::Def, Some("Scope"), ANIMATIONS, &[]);
            let mut first = true;
            for (anim, times) in anims.iter().zip(&sampled) {
                if !first {
                    doc.blank_line();
                }
                first = false;
                write_animation(
                    doc,
                    asset,
                    &plans,
                    &joint_tokens,
                    anim,
                    times,
                    &mut warnings,
                );
            }
            if rest_anim {
                let empty = AnimPlan {
                    prim: rest_anim_prim.into(),
                    joints: Vec::new(),
                    trs: Vec::new(),
                    morphs: BTreeMap::new(),
                    key_times: Vec::new(),
                    resample: false,
                    location: "default morph weights".into(),
                };
                write_animation(
                    doc,
                    asset,
                    &plans,
                    &joint_tokens,
                    &empty,
                    &[],
                    &mut warnings,
                );
            }
            doc.end_prim();
            doc.blank_line();
        }
    }

    let material_prims = material_prims(asset);
    write_materials(doc, asset, &root_path, &material_prims, image_files);
    let material_paths: Vec<String> = material_prims
        .iter()
        .map(|p| format!("{root_path}/{MATERIALS}/{p}"))
        .collect();
    for (mi, (mesh, plan)) in asset.meshes.iter().zip(&plans).enumerate() {
        write_mesh(
            doc,
            asset,
            mi,
            mesh,
            plan,
            &MeshContext {
                root_path: &root_path,
                skeleton_prims: &skeleton_prims,
                skeleton_binds: &skeleton_binds,
                options,
                material_paths: &material_paths,
                cache_clip: asset.clips.first().zip(sampled.first().map(Vec::as_slice)),
            },
            &mut warnings,
        );
        doc.blank_line();
    }

    if !anims.is_empty() {
        doc.begin_variant_set(CLIP_VARIANT_SET);
        let ranges_differ = ranges.windows(2).any(|w| w[0] != w[1]);
        for (anim, &(a, b)) in anims.iter().zip(&ranges) {
            // Clips that differ in length: each variant says its own range.
            let meta = if ranges_differ {
                vec![Field::new(
                    "customData",
                    Value::Dict(vec![
                        ("endTimeCode".into(), b.into()),
                        ("startTimeCode".into(), a.into()),
                    ]),
                )]
            } else {
                Vec::new()
            };
            doc.begin_variant(&anim.prim, &meta);
            let source = format!("{root_path}/{ANIMATIONS}/{}", anim.prim);
            for prim in &skeleton_prims {
                doc.begin_prim(Specifier::Over, None, prim, &[]);
                doc.relationship("skel:animationSource", Targets::One(&source));
                doc.end_prim();
            }
            doc.end_variant();
        }
        doc.end_variant_set();
    }
    doc.end_prim();
    Ok(warnings)
}

/// Joints a rigidly attached mesh carries as its own `xformOp`s instead of a binding: root
/// joints without children that no skin uses and no other joint hangs from, with at most
/// one clip (time samples cannot differ per clip variant). Such a joint is the transform of
/// a static mesh in the source (a USD prim's animated xformOps, a glTF node animation);
/// it stays in the Skeleton, where it drives nothing.
fn xform_joints(asset: &Asset) -> std::collections::BTreeSet<usize> {
    let mut out = std::collections::BTreeSet::new();
    if asset.clips.len() > 1 {
        return out;
    }
    let joints = asset.skeleton.joints();
    let mut has_child = vec![false; joints.len()];
    for j in joints {
        if let Some(p) = j.parent {
            if let Some(slot) = has_child.get_mut(p.get()) {
                *slot = true;
            }
        }
    }
    let in_skin = |j: usize| {
        asset
            .skins
            .iter()
            .any(|s| s.joints.iter().any(|x| x.get() == j))
    };
    for mesh in &asset.meshes {
        if let Some(j) = mesh.attached_to.map(|j| j.get()) {
            let root = joints.get(j).is_some_and(|x| x.parent.is_none());
            if root && !has_child[j] && !in_skin(j) {
                out.insert(j);
            }
        }
    }
    out
}
