//! Asset -> USDA text: the stage layout, skeleton, animations and meshes.
//!
//! See the module docs of [`super`] for what is written and why.

use std::collections::{BTreeMap, BTreeSet};

use glam::{DMat4, DQuat, Vec2, Vec3};
use rigport_model::conventions::WEIGHT_EPSILON;
use rigport_model::{
    Asset, Clip, Interpolation, Mesh, SkinBinding, Track, TrackTarget, Transform, Warning,
};

use super::names::{Namespace, Renames};
use super::sampler::{dot, Sampler};
use super::text::{array, float, matrix, put, quoted, to_half, tuple, Usda};
use super::{UsdOptions, UsdSkinning};
use crate::labels::{fallback_palette_index, mesh_label};
use crate::weights::ROW_SUM_TOLERANCE;
use crate::{ExportError, Problem};

/// Name of the Skeleton prim (extra bind poses get `Skeleton_1`, ...).
pub(crate) const SKELETON: &str = "Skeleton";
/// Name of the Scope holding the SkelAnimation prims.
pub(crate) const ANIMATIONS: &str = "Animations";
/// Name of the variant set choosing the clip bound to the skeleton.
pub(crate) const CLIP_VARIANT_SET: &str = "clip";

/// Largest element difference (translations: relative to the matrices' scale) at which two
/// bind matrices count as equal. Inverse bind matrices are `f32` (about 6e-8 relative
/// precision); 1e-6 is a few ulps of slack and far below the 1e-5 acceptance tolerance.
const BIND_TOLERANCE: f64 = 1e-6;

/// Time stamps per second when the first clip's keys fit no frame rate: milliseconds.
const FALLBACK_TIME_CODES_PER_SECOND: f64 = 1000.0;
/// Time stamps per second when there is nothing to measure (USD's own default).
const DEFAULT_TIME_CODES_PER_SECOND: f64 = 24.0;
/// Frame rates tried, after the one the key spacing suggests, to make the keys integral.
const COMMON_RATES: [f64; 9] = [24.0, 25.0, 30.0, 48.0, 50.0, 60.0, 100.0, 120.0, 240.0];
/// The slowest frame rate chosen for the stage (film's).
const MIN_FRAME_RATE: f64 = 24.0;
/// Sampling rate for cubic-spline and step tracks when the keys fit no frame rate.
const FALLBACK_RESAMPLE_FPS: f64 = 30.0;
/// Most extra samples one clip may get from resampling (keeps a mistaken hour-long clip
/// from producing gigabytes).
const MAX_RESAMPLED_FRAMES: f64 = 1_000_000.0;
/// Scale values whose half-precision rounding changes them by more than this (relative)
/// are reported.
const HALF_REPORT_TOLERANCE: f32 = 1e-5;

/// Everything that makes an asset unexportable to USD: the glTF exporter's checks
/// ([`Asset::validate`] and the rest), minus the two that are glTF limits only (an empty
/// mesh is a valid USD Mesh; UsdSkel joint indices are `int`, not `UNSIGNED_SHORT`).
pub(crate) fn check(asset: &Asset) -> Vec<Problem> {
    crate::gltf::document::check(asset)
        .into_iter()
        .filter(|p| {
            !matches!(
                p,
                Problem::EmptyMesh { .. } | Problem::PaletteTooLarge { .. }
            )
        })
        .collect()
}

/// How a mesh is bound to the skeleton.
#[derive(Clone, Copy, Debug)]
enum Binding {
    /// Not bound: a plain Mesh (model space).
    None,
    /// Skinned by skin `skin`, with Skeleton prim `skeleton` and this geomBindTransform.
    Skinned {
        skin: usize,
        skeleton: usize,
        geom_bind: DMat4,
    },
    /// Rigidly attached to a joint: constant joint influence, geomBindTransform = the
    /// joint's bind matrix (the points are in the joint's space).
    Rigid { joint: usize },
    /// Only blend shapes (no joint influence): bound to Skeleton 0 for its animation.
    MorphOnly,
}

/// One mesh as it will be written.
struct MeshPlan {
    prim: String,
    binding: Binding,
    /// BlendShape prim names, one per morph target.
    shapes: Vec<String>,
    /// The blend-shape channel tokens (unique over the stage), one per morph target.
    channels: Vec<String>,
}

/// One SkelAnimation as it will be written.
struct AnimPlan {
    prim: String,
    /// Skeleton joints animated by the clip, in skeleton order.
    joints: Vec<usize>,
    /// Translation, rotation (xyzw) and scale samplers per entry of `joints`.
    trs: Vec<[Option<Sampler>; 3]>,
    /// Morph-weight sampler per mesh (with blend shapes) animated by the clip.
    morphs: BTreeMap<usize, Sampler>,
    /// Key times in seconds (union over the kept tracks), ascending.
    key_times: Vec<f64>,
    /// Whether a step or cubic-spline track needs extra samples between keys.
    resample: bool,
    /// Location for warnings.
    location: String,
}

/// The USDA text of `asset`, with the warnings of lossy steps.
///
/// # Errors
/// [`ExportError::Invalid`] listing every problem of the asset.
pub(crate) fn build(
    asset: &Asset,
    options: &UsdOptions,
) -> Result<(String, Vec<Warning>), ExportError> {
    let problems = check(asset);
    if !problems.is_empty() {
        return Err(ExportError::Invalid { problems });
    }
    let mut warnings = Vec::new();
    let skeleton = &asset.skeleton;
    let joint_count = skeleton.len();
    let has_morphs = asset.meshes.iter().any(|m| !m.morph_targets.is_empty());
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
    let mut mesh_renames = Renames::default();
    let mut channel_ns = Namespace::default();
    let mut plans = Vec::with_capacity(asset.meshes.len());
    for (mi, mesh) in asset.meshes.iter().enumerate() {
        let (prim, renamed) = root_ns.claim(&mesh.name, "mesh");
        if renamed && !mesh.name.is_empty() {
            mesh_renames.push(&mesh.name, &prim);
        }
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
            (None, Some(j)) => Binding::Rigid { joint: j.get() },
            (None, None) if skel_root && !mesh.morph_targets.is_empty() => Binding::MorphOnly,
            (None, None) => Binding::None,
        };
        let mut shape_ns = Namespace::default();
        let mut shapes = Vec::new();
        let mut channels = Vec::new();
        for target in &mesh.morph_targets {
            let (shape, renamed) = shape_ns.claim(&target.name, "shape");
            if renamed && !target.name.is_empty() {
                mesh_renames.push(&target.name, &shape);
            }
            let (channel, _) = channel_ns.claim(&format!("{prim}_{shape}"), "shape");
            shapes.push(shape);
            channels.push(channel);
        }
        plans.push(MeshPlan {
            prim,
            binding,
            shapes,
            channels,
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

    // ------------------------------------------------------------------ text
    let mut doc = Usda::default();
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

    doc.line("#usda 1.0");
    doc.line("(");
    {
        let mut meta = |key: &str, value: &dyn Fn(&mut String)| {
            let line = doc.start();
            line.push_str("    ");
            line.push_str(key);
            line.push_str(" = ");
            value(line);
            doc.end();
        };
        meta("defaultPrim", &|s| quoted(s, &root_name));
        meta("doc", &|s| {
            quoted(
                s,
                &format!("Written by rigport {}", env!("CARGO_PKG_VERSION")),
            )
        });
        if !anims.is_empty() || rest_anim {
            let (start, end) = if start.is_finite() {
                (start, end)
            } else {
                (0.0, 0.0)
            };
            meta("endTimeCode", &|s| put(s, end));
            meta("metersPerUnit", &|s| put(s, meters_per_unit));
            meta("startTimeCode", &|s| put(s, start));
            meta("timeCodesPerSecond", &|s| put(s, tcps));
        } else {
            meta("metersPerUnit", &|s| put(s, meters_per_unit));
        }
        meta("upAxis", &|s| quoted(s, up_axis.as_str()));
    }
    doc.line(")");
    doc.blank();

    let root_type = if skel_root { "SkelRoot" } else { "Xform" };
    let header = format!("def {root_type} \"{root_name}\"");
    if let Some(first) = anims.first() {
        doc.open_meta(&header);
        doc.line("variants = {");
        {
            let line = doc.start();
            line.push_str("    string ");
            line.push_str(CLIP_VARIANT_SET);
            line.push_str(" = ");
            quoted(line, &first.prim);
            doc.end();
        }
        doc.line("}");
        {
            let line = doc.start();
            line.push_str("prepend variantSets = ");
            quoted(line, CLIP_VARIANT_SET);
            doc.end();
        }
        doc.close_meta();
        doc.open_body();
    } else {
        doc.open(&header);
    }
    if root_xform != DMat4::IDENTITY {
        write_matrices_one(&mut doc, "matrix4d xformOp:transform", &root_xform);
        doc.line("uniform token[] xformOpOrder = [\"xformOp:transform\"]");
        doc.blank();
    }

    if skel_root {
        let rest_anim_prim = "rest";
        for (k, prim) in skeleton_prims.iter().enumerate() {
            doc.open_meta(&format!("def Skeleton \"{prim}\""));
            doc.line("prepend apiSchemas = [\"SkelBindingAPI\"]");
            doc.close_meta();
            doc.open_body();
            let binds = skeleton_binds.get(k).map(Vec::as_slice).unwrap_or(&[]);
            write_matrices(&mut doc, "uniform matrix4d[] bindTransforms", binds);
            write_tokens(&mut doc, "uniform token[] joints", &joint_tokens);
            write_matrices(&mut doc, "uniform matrix4d[] restTransforms", &rest_local);
            if rest_anim {
                doc.line(&format!(
                    "rel skel:animationSource = <{root_path}/{ANIMATIONS}/{rest_anim_prim}>"
                ));
            }
            doc.close();
            doc.blank();
        }

        if !anims.is_empty() || rest_anim {
            doc.open(&format!("def Scope \"{ANIMATIONS}\""));
            let mut first = true;
            for (anim, times) in anims.iter().zip(&sampled) {
                if !first {
                    doc.blank();
                }
                first = false;
                write_animation(
                    &mut doc,
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
                    &mut doc,
                    asset,
                    &plans,
                    &joint_tokens,
                    &empty,
                    &[],
                    &mut warnings,
                );
            }
            doc.close();
            doc.blank();
        }
    }

    for (mi, (mesh, plan)) in asset.meshes.iter().zip(&plans).enumerate() {
        write_mesh(
            &mut doc,
            asset,
            mi,
            mesh,
            plan,
            &MeshContext {
                root_path: &root_path,
                skeleton_prims: &skeleton_prims,
                skeleton_binds: &skeleton_binds,
                options,
            },
            &mut warnings,
        );
        doc.blank();
    }

    if !anims.is_empty() {
        doc.line(&format!("variantSet \"{CLIP_VARIANT_SET}\" = {{"));
        let ranges_differ = ranges.windows(2).any(|w| w[0] != w[1]);
        for (anim, &(a, b)) in anims.iter().zip(&ranges) {
            let line = doc.start();
            line.push_str("    ");
            quoted(line, &anim.prim);
            if ranges_differ {
                // Clips differ in length: each variant says its own range.
                line.push_str(" (");
                doc.end();
                doc.line("        customData = {");
                let line = doc.start();
                line.push_str("            double endTimeCode = ");
                put(line, b);
                doc.end();
                let line = doc.start();
                line.push_str("            double startTimeCode = ");
                put(line, a);
                doc.end();
                doc.line("        }");
                doc.line("    ) {");
            } else {
                line.push_str(" {");
                doc.end();
            }
            for prim in &skeleton_prims {
                doc.line(&format!("        over \"{prim}\""));
                doc.line("        {");
                doc.line(&format!(
                    "            rel skel:animationSource = <{root_path}/{ANIMATIONS}/{}>",
                    anim.prim
                ));
                doc.line("        }");
            }
            doc.line("    }");
        }
        doc.line("}");
    }
    doc.close();
    Ok((doc.finish(), warnings))
}

/// The UsdSkel joint path token of every joint, and the renames made.
fn joint_tokens(asset: &Asset) -> (Vec<String>, Renames) {
    let joints = asset.skeleton.joints();
    let mut child_ns: Vec<Namespace> = (0..joints.len()).map(|_| Namespace::default()).collect();
    let mut root_ns = Namespace::default();
    let mut renames = Renames::default();
    let mut tokens: Vec<String> = Vec::with_capacity(joints.len());
    for joint in joints {
        let parent = joint.parent.map(|p| p.get());
        let ns = match parent.and_then(|p| child_ns.get_mut(p)) {
            Some(ns) => ns,
            None => &mut root_ns,
        };
        let (name, renamed) = ns.claim(&joint.name, "joint");
        if renamed {
            renames.push(&joint.name, &name);
        }
        // Parents come first, so the parent's token exists.
        let token = match parent.and_then(|p| tokens.get(p)) {
            Some(parent_token) => format!("{parent_token}/{name}"),
            None => name,
        };
        tokens.push(token);
    }
    (tokens, renames)
}

/// `T · R · S` in `f64`, the rotation normalized.
fn transform_d(t: &Transform) -> DMat4 {
    let q = t.rotation.to_array().map(f64::from);
    let len = dot(q, q).sqrt();
    let q = if len > 0.0 {
        q.map(|c| c / len)
    } else {
        [0.0, 0.0, 0.0, 1.0]
    };
    DMat4::from_scale_rotation_translation(
        t.scale.as_dvec3(),
        DQuat::from_xyzw(q[0], q[1], q[2], q[3]),
        t.translation.as_dvec3(),
    )
}

/// Whether two matrices agree within [`BIND_TOLERANCE`] (translations relative to their
/// magnitude, at least 1).
fn near(a: &DMat4, b: &DMat4) -> bool {
    let scale = a
        .w_axis
        .truncate()
        .abs()
        .max(b.w_axis.truncate().abs())
        .max_element()
        .max(1.0);
    let (a, b) = (a.to_cols_array_2d(), b.to_cols_array_2d());
    a.iter().zip(&b).enumerate().all(|(c, (ca, cb))| {
        ca.iter().zip(cb).enumerate().all(|(r, (x, y))| {
            let tol = if c == 3 && r < 3 {
                BIND_TOLERANCE * scale
            } else {
                BIND_TOLERANCE
            };
            (x - y).abs() <= tol
        })
    })
}

/// The bind matrices of each Skeleton prim, and for each skin its Skeleton prim and
/// geomBindTransform.
///
/// Skeleton 0's bind matrix of a joint is the inverse of the first skin's inverse bind
/// matrix that names it, else the joint's rest model matrix. A skin whose inverse bind
/// matrices disagree is placed with a common geomBindTransform `G` when one exists (UsdSkel
/// skins `jointWorld · bind⁻¹ · G · p`, rigport `jointWorld · invBind · p`, so
/// `G = bind · invBind` must be the same for all its joints), else on a Skeleton prim of its
/// own with the same joints and animation.
fn bind_poses(
    asset: &Asset,
    rest_model: &[DMat4],
    warnings: &mut Vec<Warning>,
) -> (Vec<Vec<DMat4>>, Vec<(usize, DMat4)>) {
    let mut first: Vec<Option<DMat4>> = vec![None; rest_model.len()];
    for skin in &asset.skins {
        for (j, ib) in skin.joints.iter().zip(&skin.inv_bind) {
            if let Some(slot @ None) = first.get_mut(j.get()) {
                *slot = Some(ib.as_dmat4().inverse());
            }
        }
    }
    let bind0: Vec<DMat4> = first
        .into_iter()
        .zip(rest_model)
        .map(|(b, rest)| b.unwrap_or(*rest))
        .collect();
    let mut binds = vec![bind0];
    let mut places = Vec::with_capacity(asset.skins.len());
    for (si, skin) in asset.skins.iter().enumerate() {
        let place = place_skin(&mut binds, skin);
        if place.0 > 0 && place.0 == binds.len() - 1 {
            let mesh = asset.meshes.get(skin.mesh.get());
            warnings.push(Warning::Note {
                location: format!(
                    "skin {si} (mesh {:?})",
                    mesh.map(|m| mesh_label(skin.mesh.get(), m))
                        .unwrap_or_default()
                ),
                message: format!(
                    "its bind pose differs from that of earlier skins; written as Skeleton prim \
                     {SKELETON}_{} with the same joints and animation",
                    place.0
                ),
            });
        }
        places.push(place);
    }
    (binds, places)
}

/// Finds or makes the Skeleton prim for `skin` (see [`bind_poses`]).
fn place_skin(binds: &mut Vec<Vec<DMat4>>, skin: &SkinBinding) -> (usize, DMat4) {
    let inv: Vec<(usize, DMat4)> = skin
        .joints
        .iter()
        .zip(&skin.inv_bind)
        .map(|(j, ib)| (j.get(), ib.as_dmat4()))
        .collect();
    let g_of = |bind: &[DMat4]| -> Vec<DMat4> {
        inv.iter()
            .filter_map(|(j, ib)| bind.get(*j).map(|b| *b * *ib))
            .collect()
    };
    for (k, bind) in binds.iter().enumerate() {
        let g = g_of(bind);
        if g.iter().all(|m| near(m, &DMat4::IDENTITY)) {
            return (k, DMat4::IDENTITY);
        }
        if k == 0 {
            if let Some(g0) = g.first() {
                if g.iter().all(|m| near(m, g0)) {
                    return (0, *g0);
                }
            }
        }
    }
    let mut own = binds.first().cloned().unwrap_or_default();
    for (j, ib) in &inv {
        if let Some(slot) = own.get_mut(*j) {
            *slot = ib.inverse();
        }
    }
    binds.push(own);
    (binds.len() - 1, DMat4::IDENTITY)
}

/// Picks the tracks of one clip that will be written, reporting the others.
///
/// A joint whose tracks in the clip all hold its rest value (as Blender's glTF exporter
/// writes for every bone) is left out of the SkelAnimation's `joints`: UsdSkel then takes
/// it from the Skeleton's `restTransforms`, the same transform in double precision and
/// without half-precision scales. Its keys still count for the clip's times.
fn plan_clip(
    asset: &Asset,
    clip: &Clip,
    prim: String,
    plans: &[MeshPlan],
    warnings: &mut Vec<Warning>,
) -> AnimPlan {
    let location = format!("clip {:?}", clip.name);
    let mut trs: BTreeMap<usize, [Option<&Track>; 3]> = BTreeMap::new();
    let mut morphs = BTreeMap::new();
    let mut seen = BTreeSet::new();
    let mut times: Vec<f32> = Vec::new();
    let mut resample = false;
    let needs_frames = |track: &Track| {
        track.times.len() >= 2
            && matches!(
                track.interpolation,
                Interpolation::Step | Interpolation::CubicSpline
            )
    };
    for (ti, track) in clip.tracks.iter().enumerate() {
        let dropped = |why: String| Warning::Repaired {
            location: format!("{location} track {ti}"),
            message: format!("track dropped: {why}"),
        };
        if !seen.insert(track.target) {
            warnings.push(dropped(
                "an earlier track of this clip animates the same property".into(),
            ));
            continue;
        }
        match track.target {
            TrackTarget::Translation(j) | TrackTarget::Rotation(j) | TrackTarget::Scale(j) => {
                let slot = match track.target {
                    TrackTarget::Translation(_) => 0,
                    TrackTarget::Rotation(_) => 1,
                    _ => 2,
                };
                let entry = trs.entry(j.get()).or_insert([None, None, None]);
                entry[slot] = Some(track);
            }
            TrackTarget::MorphWeights(m) => {
                let mi = m.get();
                let targets = plans.get(mi).map_or(0, |p| p.channels.len());
                let label = asset
                    .meshes
                    .get(mi)
                    .map(|mesh| mesh_label(mi, mesh))
                    .unwrap_or_default();
                if targets == 0 {
                    warnings.push(dropped(format!("mesh {label:?} has no morph targets")));
                    continue;
                }
                if track.components() != targets {
                    warnings.push(dropped(format!(
                        "{} weights per key for the {targets} morph targets of mesh {label:?}",
                        track.components()
                    )));
                    continue;
                }
                resample |= needs_frames(track);
                morphs.insert(mi, Sampler::new(track));
            }
        }
        times.extend_from_slice(&track.times);
    }
    times.sort_by(f32::total_cmp);
    times.dedup_by(|a, b| a.to_bits() == b.to_bits());
    let joints_rest = asset.skeleton.joints();
    let mut joints = Vec::with_capacity(trs.len());
    let mut samplers = Vec::with_capacity(trs.len());
    for (j, tracks) in trs {
        let Some(rest) = joints_rest.get(j).map(|joint| joint.rest_local) else {
            continue;
        };
        if tracks.iter().flatten().all(|t| at_rest(t, &rest)) {
            continue;
        }
        resample |= tracks.iter().flatten().any(|t| needs_frames(t));
        joints.push(j);
        samplers.push(tracks.map(|t| t.map(Sampler::new)));
    }
    AnimPlan {
        prim,
        joints,
        trs: samplers,
        morphs,
        key_times: times.into_iter().map(f64::from).collect(),
        resample,
        location,
    }
}

/// Whether every key of a joint track holds the joint's rest value (cubic tangents zero):
/// translations and scales exactly (`-0 == 0`), rotations as the same unit quaternion up to sign
/// within 1e-7 per component (normalization noise).
fn at_rest(track: &Track, rest: &Transform) -> bool {
    let cubic = track.interpolation == Interpolation::CubicSpline;
    let c = track.components();
    let value: Vec<f32> = match track.target {
        TrackTarget::Translation(_) => rest.translation.to_array().to_vec(),
        TrackTarget::Scale(_) => rest.scale.to_array().to_vec(),
        TrackTarget::Rotation(_) => rest.rotation.to_array().to_vec(),
        TrackTarget::MorphWeights(_) => return false,
    };
    let rest_q = unit(rest.rotation.to_array().map(f64::from));
    let stride = if cubic { 3 * c } else { c };
    if c == 0 || track.values.len() != stride * track.times.len() {
        return false;
    }
    track.values.chunks_exact(stride).all(|key| {
        let (tangents_zero, v) = if cubic {
            let zero = key[..c].iter().chain(&key[2 * c..]).all(|&x| x == 0.0);
            (zero, &key[c..2 * c])
        } else {
            (true, key)
        };
        let same = match track.target {
            TrackTarget::Rotation(_) => {
                let q = unit([v[0], v[1], v[2], v[3]].map(f64::from));
                let sign = if dot(q.map(f64::from), rest_q.map(f64::from)) < 0.0 {
                    -1.0
                } else {
                    1.0
                };
                q.iter()
                    .zip(&rest_q)
                    .all(|(a, b)| (sign * a - b).abs() <= 1e-7)
            }
            _ => v.iter().zip(&value).all(|(a, b)| a == b),
        };
        tangents_zero && same
    })
}

/// Relative precision of an `f32` key time, with slack: 2⁻²¹ is four times the largest
/// relative rounding error of one `f32` operation (2⁻²³ spacing, halved, doubled twice), so
/// times computed as `k · frame_time` in `f32` pass while a frame off does not.
const F32_NOISE: f64 = 4.768_371_582_031_25e-7; // 2^-21

/// The stage rate for a clip's key times (seconds, ascending, distinct):
///
/// 1. three or more keys evenly spaced (within `f32` noise) at 24 or more per second: that rate,
///    `1 / spacing`, rounded to an integer when within `f32` noise of one, so BVH's
///    `Frame Time: 0.0333333` gives 30.00003 and keys land on integral time codes exactly
///    (rounding to 30 would shift key k by k·1e-6 frames, 1e-5 of the motion by the end
///    of a fast clip);
/// 2. else the first of: the rate the smallest key interval suggests (when at least 24),
///    24, 25, 30, 48, 50, 60, 100, 120, 240, and for sparse keys (say every 0.5 s, which
///    fit 2 per second, too slow to play or to resample) the smallest multiple of the
///    suggested rate from 24 up, that puts every key on an integral frame (within
///    [`frame_noise`]).
///
/// `None` for fewer than two keys or no fit.
pub(crate) fn frame_rate(times: &[f64]) -> Option<f64> {
    let (&first, &last) = (times.first()?, times.last()?);
    let n = times.len();
    if n < 2 || last <= first {
        return None;
    }
    let spacing = (last - first) / (n - 1) as f64;
    // Two keys are always evenly spaced; a rate needs three.
    let even = n >= 3
        && times.iter().enumerate().all(|(k, &t)| {
            (t - (first + k as f64 * spacing)).abs() <= t.abs().max(spacing) * F32_NOISE
        });
    if even {
        let rate = 1.0 / spacing;
        if (MIN_FRAME_RATE..=10_000.0).contains(&rate) {
            let whole = rate.round();
            return Some(if (rate - whole).abs() <= rate * F32_NOISE {
                whole
            } else {
                rate
            });
        }
    }
    let min_gap = times
        .windows(2)
        .map(|w| w[1] - w[0])
        .filter(|&d| d > 0.0)
        .fold(f64::INFINITY, f64::min);
    let suggested = (1.0 / min_gap).round();
    // The smallest gap's rate exactly when it is a ratio with a small denominator
    // (37.5 = 75/2 keys per second): keys dropped by a reducer leave uneven gaps, but
    // every key is still on that rate's frames. The gap of two f32 times is imprecise, so
    // the rate is refined over the whole span (frames between the first and last key at
    // the gap's rate), then snapped to k/n only when within f32 noise.
    let span = last - first;
    let frames = (span / min_gap).round();
    let exact = (frames >= 1.0).then(|| frames / span).and_then(|r| {
        (1..=8).find_map(|k| {
            let rk = r * k as f64;
            let whole = rk.round();
            ((rk - whole).abs() <= rk * F32_NOISE * 4.0 && whole > 0.0).then(|| whole / k as f64)
        })
    });
    let candidates: Vec<f64> = if suggested >= MIN_FRAME_RATE {
        exact
            .filter(|&e| e >= MIN_FRAME_RATE && e != suggested)
            .into_iter()
            .chain(std::iter::once(suggested))
            .chain(COMMON_RATES)
            .collect()
    } else {
        let multiple = suggested * (MIN_FRAME_RATE / suggested.max(1.0)).ceil();
        COMMON_RATES.into_iter().chain([multiple]).collect()
    };
    candidates
        .into_iter()
        .filter(|r| (1.0..=10_000.0).contains(r))
        .find(|&r| {
            times.iter().all(|&t| {
                let f = t * r;
                (f - f.round()).abs() <= frame_noise(f)
            })
        })
}

/// How far from an integer a time code may be and still count as on a frame: 1e-3
/// frames, or the `f32` noise of the key time it came from when larger. Key times written
/// with a few decimals (glTF exporters' `0.0416666` for 1/24 s, accumulated in `f32`) land
/// within 1e-5 frames of a frame; 1e-3 keeps real sub-frame keys apart. `check_usd.py`
/// maps dump times to time codes with the same rule.
fn frame_noise(tc: f64) -> f64 {
    1e-3_f64.max(tc.abs() * F32_NOISE)
}

/// A time code snapped to the nearest integer when within `f32` noise of it (see
/// [`frame_noise`]), so keys on frames are written as whole frames.
fn snap(tc: f64) -> f64 {
    let n = tc.round();
    if (tc - n).abs() <= frame_noise(tc) {
        // `+ 0.0` turns -0 into 0.
        n + 0.0
    } else {
        tc
    }
}

/// The `(time code, seconds)` samples of a clip: every key time, plus every frame at
/// `resample_fps` between the first and last key when a step or cubic-spline track needs
/// them (USD interpolates time samples linearly, slerping quaternions). Time codes that
/// snap to the same value are written once, keys first.
fn sample_times(
    anim: &AnimPlan,
    tcps: f64,
    resample_fps: f64,
    warnings: &mut Vec<Warning>,
) -> Vec<(f64, f64)> {
    let mut out: Vec<(f64, f64)> = Vec::with_capacity(anim.key_times.len());
    for &t in &anim.key_times {
        let tc = snap(t * tcps);
        if out.last().is_none_or(|&(last, _)| last != tc) {
            out.push((tc, t));
        }
    }
    let (Some(&first), Some(&last)) = (anim.key_times.first(), anim.key_times.last()) else {
        return out;
    };
    if !anim.resample {
        return out;
    }
    let k0 = (first * resample_fps).ceil();
    let k1 = (last * resample_fps).floor();
    if k1 - k0 > MAX_RESAMPLED_FRAMES {
        warnings.push(Warning::Repaired {
            location: anim.location.clone(),
            message: format!(
                "step and cubic-spline tracks sampled at their keys only ({} frames at {resample_fps} fps would be too many); USD interpolates linearly between them",
                k1 - k0
            ),
        });
        return out;
    }
    let keys: Vec<f64> = out.iter().map(|&(tc, _)| tc).collect();
    let tol = frame_noise(last * tcps);
    let mut k = k0;
    while k <= k1 {
        let t = k / resample_fps;
        let tc = snap(t * tcps);
        let i = keys.partition_point(|&x| x < tc);
        let clash = [i.checked_sub(1), Some(i)]
            .into_iter()
            .flatten()
            .filter_map(|i| keys.get(i))
            .any(|&x| (x - tc).abs() <= tol);
        if !clash {
            out.push((tc, t));
        }
        k += 1.0;
    }
    out.sort_by(|a, b| a.0.total_cmp(&b.0));
    warnings.push(Warning::Repaired {
        location: anim.location.clone(),
        message: format!(
            "step and cubic-spline tracks sampled at {resample_fps} fps: USD interpolates time \
             samples linearly, so the motion is exact at every key and every 1/{resample_fps} s"
        ),
    });
    out
}

/// Writes `decl = [m, m, ...]` of matrices.
fn write_matrices(doc: &mut Usda, decl: &str, ms: &[DMat4]) {
    let line = doc.start();
    line.push_str(decl);
    line.push_str(" = ");
    array(line, ms, matrix);
    doc.end();
}

/// Writes `decl = ( (..), .. )`, one matrix (transposed to USD's row vectors).
fn write_matrices_one(doc: &mut Usda, decl: &str, m: &DMat4) {
    let line = doc.start();
    line.push_str(decl);
    line.push_str(" = ");
    matrix(line, m);
    doc.end();
}

/// Writes `decl = ["a", "b", ...]`.
fn write_tokens(doc: &mut Usda, decl: &str, tokens: &[String]) {
    let line = doc.start();
    line.push_str(decl);
    line.push_str(" = ");
    array(line, tokens, |s, t| quoted(s, t));
    doc.end();
}

/// Appends a quaternion `(w, x, y, z)` (USDA's quatf order) from xyzw.
fn put_quat(out: &mut String, q: [f32; 4]) {
    tuple(out, &[q[3], q[0], q[1], q[2]]);
}

/// One pose of an animation's joints: translations, rotations (xyzw), scales (as written,
/// half-rounded).
struct PoseSample {
    t: Vec<[f32; 3]>,
    r: Vec<[f32; 4]>,
    s: Vec<[f32; 3]>,
}

/// Writes one SkelAnimation: defaults (the rest pose and default morph weights), then
/// time samples at `times`.
fn write_animation(
    doc: &mut Usda,
    asset: &Asset,
    plans: &[MeshPlan],
    joint_tokens: &[String],
    anim: &AnimPlan,
    times: &[(f64, f64)],
    warnings: &mut Vec<Warning>,
) {
    let joints = asset.skeleton.joints();
    let rest: Vec<Transform> = anim
        .joints
        .iter()
        .filter_map(|&j| joints.get(j).map(|joint| joint.rest_local))
        .collect();
    let mut half_error = HalfError::default();
    let rest_pose = PoseSample {
        t: rest.iter().map(|r| r.translation.to_array()).collect(),
        r: rest
            .iter()
            .map(|r| unit(r.rotation.to_array().map(f64::from)))
            .collect(),
        s: rest
            .iter()
            .map(|r| half_error.round(r.scale.to_array()))
            .collect(),
    };
    let mut poses: Vec<PoseSample> = Vec::with_capacity(times.len());
    let mut value = [0.0_f64; 4];
    for &(_, seconds) in times {
        if anim.joints.is_empty() {
            break;
        }
        let mut pose = PoseSample {
            t: Vec::with_capacity(rest.len()),
            r: Vec::with_capacity(rest.len()),
            s: Vec::with_capacity(rest.len()),
        };
        for (k, (samplers, rest)) in anim.trs.iter().zip(&rest).enumerate() {
            let [st, sr, ss] = samplers;
            pose.t.push(match st {
                Some(s) => {
                    s.sample(seconds, &mut value);
                    [value[0], value[1], value[2]].map(|v| v as f32)
                }
                None => rest.translation.to_array(),
            });
            let mut q = match sr {
                Some(s) => {
                    s.sample(seconds, &mut value);
                    unit(value)
                }
                None => unit(rest.rotation.to_array().map(f64::from)),
            };
            // Sign-continuous samples, so any interpolation between them takes the short arc.
            if let Some(prev) = poses.last().and_then(|p| p.r.get(k)) {
                if dot(prev.map(f64::from), q.map(f64::from)) < 0.0 {
                    q = q.map(|c| -c);
                }
            }
            pose.r.push(q);
            pose.s.push(match ss {
                Some(s) => {
                    s.sample(seconds, &mut value);
                    half_error.round([value[0], value[1], value[2]].map(|v| v as f32))
                }
                None => half_error.round(rest.scale.to_array()),
            });
        }
        poses.push(pose);
    }
    if half_error.worst > HALF_REPORT_TOLERANCE {
        warnings.push(Warning::Repaired {
            location: anim.location.clone(),
            message: format!(
                "{} scale values rounded to half precision (SkelAnimation scales are half3[]); largest relative change {:.2e}",
                half_error.count, half_error.worst
            ),
        });
    }

    // Blend-shape channels of every mesh, in mesh order.
    let channels: Vec<&String> = plans.iter().flat_map(|p| p.channels.iter()).collect();
    let default_weights: Vec<f32> = plans
        .iter()
        .zip(&asset.meshes)
        .flat_map(|(p, m)| {
            (0..p.channels.len()).map(|k| m.morph_weights.get(k).copied().unwrap_or(0.0))
        })
        .collect();

    doc.open(&format!("def SkelAnimation \"{}\"", anim.prim));
    if !channels.is_empty() {
        let line = doc.start();
        line.push_str("uniform token[] blendShapes = ");
        array(line, &channels, |s, c| quoted(s, c));
        doc.end();
        let line = doc.start();
        line.push_str("float[] blendShapeWeights = ");
        array(line, &default_weights, |s, w| float(s, *w));
        doc.end();
        if !anim.morphs.is_empty() && !times.is_empty() {
            doc.line("float[] blendShapeWeights.timeSamples = {");
            let mut weights = default_weights.clone();
            let mut buf = Vec::new();
            for &(tc, seconds) in times {
                let mut offset = 0;
                for (mi, plan) in plans.iter().enumerate() {
                    let n = plan.channels.len();
                    if let Some(sampler) = anim.morphs.get(&mi) {
                        buf.resize(n, 0.0);
                        sampler.sample(seconds, &mut buf);
                        for (w, v) in weights.iter_mut().skip(offset).zip(&buf) {
                            *w = *v as f32;
                        }
                    }
                    offset += n;
                }
                let line = doc.start();
                line.push_str("    ");
                put(line, tc);
                line.push_str(": ");
                array(line, &weights, |s, w| float(s, *w));
                line.push(',');
                doc.end();
            }
            doc.line("}");
        }
    }
    let tokens: Vec<&String> = anim
        .joints
        .iter()
        .filter_map(|&j| joint_tokens.get(j))
        .collect();
    let line = doc.start();
    line.push_str("uniform token[] joints = ");
    array(line, &tokens, |s, t| quoted(s, t));
    doc.end();

    type Put = fn(&mut String, &PoseSample);
    let attributes: [(&str, Put); 3] = [
        ("quatf[] rotations", |s, p| {
            array(s, &p.r, |s, q| put_quat(s, *q))
        }),
        ("half3[] scales", |s, p| array(s, &p.s, |s, v| tuple(s, v))),
        ("float3[] translations", |s, p| {
            array(s, &p.t, |s, v| tuple(s, v))
        }),
    ];
    for (decl, write) in attributes {
        let line = doc.start();
        line.push_str(decl);
        line.push_str(" = ");
        write(line, &rest_pose);
        doc.end();
        if !poses.is_empty() {
            doc.line(&format!("{decl}.timeSamples = {{"));
            for (&(tc, _), pose) in times.iter().zip(&poses) {
                let line = doc.start();
                line.push_str("    ");
                put(line, tc);
                line.push_str(": ");
                write(line, pose);
                line.push(',');
                doc.end();
            }
            doc.line("}");
        }
    }
    doc.close();
}

/// Tracks the largest relative change made by rounding scales to half precision.
#[derive(Default)]
struct HalfError {
    worst: f32,
    count: usize,
}

impl HalfError {
    /// Rounds to half precision, recording the change.
    fn round(&mut self, v: [f32; 3]) -> [f32; 3] {
        v.map(|x| {
            let h = to_half(x);
            let rel = if x == 0.0 { 0.0 } else { ((h - x) / x).abs() };
            if rel > HALF_REPORT_TOLERANCE {
                self.count += 1;
            }
            self.worst = self.worst.max(rel);
            h
        })
    }
}

/// A unit quaternion (xyzw, `f32`) from an `f64` one.
fn unit(q: [f64; 4]) -> [f32; 4] {
    let len = dot(q, q).sqrt();
    if len > 0.0 {
        q.map(|c| (c / len) as f32)
    } else {
        [0.0, 0.0, 0.0, 1.0]
    }
}

/// What [`write_mesh`] needs besides the mesh.
struct MeshContext<'a> {
    root_path: &'a str,
    skeleton_prims: &'a [String],
    skeleton_binds: &'a [Vec<DMat4>],
    options: &'a UsdOptions,
}

/// Writes `decl = [..] ( interpolation = "vertex" [elementSize = n] )`.
fn write_primvar(
    doc: &mut Usda,
    decl: &str,
    value: impl FnOnce(&mut String),
    element_size: Option<usize>,
    interpolation: &str,
) {
    let line = doc.start();
    line.push_str(decl);
    line.push_str(" = ");
    value(line);
    line.push_str(" (");
    doc.end();
    if let Some(n) = element_size {
        doc.line(&format!("    elementSize = {n}"));
    }
    doc.line(&format!("    interpolation = \"{interpolation}\""));
    doc.line(")");
}

/// Writes one Mesh prim (and its BlendShape children).
fn write_mesh(
    doc: &mut Usda,
    asset: &Asset,
    mi: usize,
    mesh: &Mesh,
    plan: &MeshPlan,
    ctx: &MeshContext<'_>,
    warnings: &mut Vec<Warning>,
) {
    let label = mesh_label(mi, mesh);
    let header = format!("def Mesh \"{}\"", plan.prim);
    if matches!(plan.binding, Binding::None) {
        doc.open(&header);
    } else {
        doc.open_meta(&header);
        doc.line("prepend apiSchemas = [\"SkelBindingAPI\"]");
        doc.close_meta();
        doc.open_body();
    }

    if let Some((lo, hi)) = mesh.bounds() {
        let line = doc.start();
        line.push_str("float3[] extent = ");
        array(line, &[lo, hi], |s, v| tuple(s, &v.to_array()));
        doc.end();
    }
    let line = doc.start();
    line.push_str("int[] faceVertexCounts = ");
    array(line, &mesh.triangles, |s, _| s.push('3'));
    doc.end();
    // Triangles are counter-clockwise (glTF's and the model's rule), USD's default
    // `orientation = "rightHanded"`: written as they are.
    let line = doc.start();
    line.push_str("int[] faceVertexIndices = ");
    let flat: Vec<u32> = mesh.triangles.iter().flatten().copied().collect();
    array(line, &flat, |s, i| put(s, i));
    doc.end();

    let normals = mesh_normals(mesh, &label, warnings);
    write_primvar(
        doc,
        "normal3f[] normals",
        |s| array(s, &normals, |s, n| tuple(s, &n.to_array())),
        None,
        "vertex",
    );
    let line = doc.start();
    line.push_str("point3f[] points = ");
    array(line, &mesh.positions, |s, p| tuple(s, &p.to_array()));
    doc.end();

    // The dump of `rigport eval` lists vertices by source vertex; say how points map to
    // them when the mesh split vertices (seams).
    let identity = mesh
        .source_vertex
        .iter()
        .enumerate()
        .all(|(v, &s)| s as usize == v);
    if !identity {
        write_primvar(
            doc,
            "int[] primvars:rigport:sourceVertex",
            |s| array(s, &mesh.source_vertex, |s, v| put(s, v)),
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
                "int[] primvars:skel:jointIndices",
                |s| array(s, &[joint], |s, j| put(s, j)),
                Some(1),
                "constant",
            );
            write_primvar(
                doc,
                "float[] primvars:skel:jointWeights",
                |s| s.push_str("[1]"),
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
                let rows = skin_rows(asset, skin, binding, &label, warnings);
                write_geom_bind(doc, &geom_bind);
                write_primvar(
                    doc,
                    "int[] primvars:skel:jointIndices",
                    |s| array(s, &rows.indices, |s, j| put(s, j)),
                    Some(rows.element_size),
                    "vertex",
                );
                write_primvar(
                    doc,
                    "float[] primvars:skel:jointWeights",
                    |s| array(s, &rows.weights, |s, w| float(s, *w)),
                    Some(rows.element_size),
                    "vertex",
                );
                if ctx.options.skinning.unwrap_or(binding.method) == UsdSkinning::Dqs {
                    doc.line("uniform token primvars:skel:skinningMethod = \"dualQuaternion\"");
                }
            }
            skeleton_rel = Some(skeleton_path(skeleton));
        }
    }

    if let Some(uvs) = &mesh.uvs {
        // The model's UVs follow glTF (origin top-left, v down); USD's st have their origin
        // bottom-left with t up.
        let st: Vec<Vec2> = uvs.iter().map(|uv| Vec2::new(uv.x, 1.0 - uv.y)).collect();
        write_primvar(
            doc,
            "texCoord2f[] primvars:st",
            |s| array(s, &st, |s, v| tuple(s, &v.to_array())),
            None,
            "vertex",
        );
    }

    let mesh_path = format!("{}/{}", ctx.root_path, plan.prim);
    if !plan.channels.is_empty() && skeleton_rel.is_some() {
        write_tokens(doc, "uniform token[] skel:blendShapes", &plan.channels);
        let line = doc.start();
        line.push_str("rel skel:blendShapeTargets = ");
        array(line, &plan.shapes, |s, shape| {
            s.push('<');
            s.push_str(&mesh_path);
            s.push('/');
            s.push_str(shape);
            s.push('>');
        });
        doc.end();
    }
    if let Some(path) = &skeleton_rel {
        doc.line(&format!("rel skel:skeleton = <{path}>"));
    }
    // rigport meshes are polygonal; USD's fallback scheme would subdivide them.
    doc.line("uniform token subdivisionScheme = \"none\"");

    if skeleton_rel.is_some() {
        for (target, shape) in mesh.morph_targets.iter().zip(&plan.shapes) {
            doc.blank();
            write_blend_shape(doc, target, shape);
        }
    }
    doc.close();
}

/// `matrix4d primvars:skel:geomBindTransform = ...`.
fn write_geom_bind(doc: &mut Usda, m: &DMat4) {
    let line = doc.start();
    line.push_str("matrix4d primvars:skel:geomBindTransform = ");
    matrix(line, m);
    doc.end();
}

/// One BlendShape prim: offsets (sparse with `pointIndices` when some points do not move).
fn write_blend_shape(doc: &mut Usda, target: &rigport_model::MorphTarget, prim: &str) {
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
    doc.open(&format!("def BlendShape \"{prim}\""));
    if let Some(normals) = &target.normal_deltas {
        let line = doc.start();
        line.push_str("uniform vector3f[] normalOffsets = ");
        array(line, &pick(normals), |s, v| tuple(s, &v.to_array()));
        doc.end();
    }
    let line = doc.start();
    line.push_str("uniform vector3f[] offsets = ");
    array(line, &pick(&target.position_deltas), |s, v| {
        tuple(s, &v.to_array())
    });
    doc.end();
    if !dense {
        let line = doc.start();
        line.push_str("uniform int[] pointIndices = ");
        array(line, &moved, |s, v| put(s, v));
        doc.end();
    }
    doc.close();
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

/// Flattened UsdSkel influences of one skinned mesh.
struct SkinRows {
    /// Influences per point (the largest row), at least 1.
    element_size: usize,
    /// Skeleton joint indices, `element_size` per point, zero-padded.
    indices: Vec<u32>,
    /// Weights, `element_size` per point, summing to 1 per point, zero-padded.
    weights: Vec<f32>,
}

/// The influences of `skin` as UsdSkel primvars: palette entries mapped to skeleton joint
/// indices, entries of one joint merged, weights below [`WEIGHT_EPSILON`] of the row's
/// total dropped (arithmetic noise, as for glTF), sorted by weight (largest first, ties by
/// joint), renormalized in `f64`. No limit on the count. A point without influence is bound
/// with weight 1 to the skin's root joint (UsdSkel would move it to the origin), and
/// reported, as is every row whose sum was off by more than the glTF exporter's tolerance.
fn skin_rows(
    asset: &Asset,
    si: usize,
    skin: &SkinBinding,
    label: &str,
    warnings: &mut Vec<Warning>,
) -> SkinRows {
    let fallback_palette = fallback_palette_index(&asset.skeleton, &skin.joints);
    let fallback = skin.joints.get(fallback_palette).map_or(0, |j| j.0);
    let mut rows: Vec<Vec<(u32, f64)>> = Vec::with_capacity(skin.influences.vertex_count());
    let (mut unbound, mut renormalized, mut max_error) = (0_usize, 0_usize, 0.0_f64);
    for row in skin.influences.rows() {
        let mut merged: BTreeMap<u32, f64> = BTreeMap::new();
        for inf in row {
            if let Some(j) = skin.joints.get(inf.joint as usize) {
                *merged.entry(j.0).or_default() += f64::from(inf.weight);
            }
        }
        let total: f64 = merged.values().sum();
        let mut kept: Vec<(u32, f64)> = merged
            .into_iter()
            .filter(|&(_, w)| total > 0.0 && w / total >= f64::from(WEIGHT_EPSILON))
            .collect();
        if kept.is_empty() {
            unbound += 1;
            rows.push(vec![(fallback, 1.0)]);
            continue;
        }
        let kept_total: f64 = kept.iter().map(|&(_, w)| w).sum();
        let error = (kept_total - 1.0).abs();
        if error > ROW_SUM_TOLERANCE {
            renormalized += 1;
            max_error = max_error.max(error);
        }
        kept.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
        for entry in &mut kept {
            entry.1 /= kept_total;
        }
        rows.push(kept);
    }
    let element_size = rows.iter().map(Vec::len).max().unwrap_or(0).max(1);
    let mut indices = Vec::with_capacity(rows.len() * element_size);
    let mut weights = Vec::with_capacity(rows.len() * element_size);
    for row in &rows {
        for slot in 0..element_size {
            let (j, w) = row.get(slot).copied().unwrap_or((0, 0.0));
            indices.push(j);
            weights.push(w as f32);
        }
    }
    if renormalized > 0 {
        warnings.push(Warning::WeightsRenormalized {
            source: format!("mesh {label:?} (skin {si})"),
            rows: renormalized,
            max_row_sum_error: max_error as f32,
        });
    }
    if unbound > 0 {
        let root = asset
            .skeleton
            .joints()
            .get(fallback as usize)
            .map(|j| j.name.as_str())
            .unwrap_or_default();
        warnings.push(Warning::Repaired {
            location: format!("mesh {label:?} (skin {si})"),
            message: format!(
                "{unbound} {} had no influence; bound with weight 1 to the skin's root joint {root:?}",
                if unbound == 1 { "vertex" } else { "vertices" }
            ),
        });
    }
    SkinRows {
        element_size,
        indices,
        weights,
    }
}
