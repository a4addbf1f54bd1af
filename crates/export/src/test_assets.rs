//! Test assets built in code, one feature each where possible.
//!
//! Shared by the unit tests and `examples/write_samples.rs` (which writes them for
//! Khronos glTF-Validator runs), so both check the same data.

use rigport_model::glam::{Mat4, Quat, Vec2, Vec3};
use rigport_model::{
    Asset, Clip, Influence, Influences, Interpolation, Joint, JointIndex, Mesh, MeshIndex,
    MorphTarget, Skeleton, SkinBinding, Track, TrackTarget, Transform,
};

/// Rings and segments of the skinned cylinder: 10 × 20 = 200 vertices.
const RINGS: usize = 10;
const SEGMENTS: usize = 20;

/// A chain of `n` joints along +Y, one unit apart; the second joint has a rest rotation.
/// Joint names: `root`, `mid`, `tip` for `n == 3`, else `j0`, `j1`, ...
pub(crate) fn chain(n: usize) -> Skeleton {
    let joints = (0..n)
        .map(|i| {
            let name = if n == 3 {
                ["root", "mid", "tip"][i].to_string()
            } else {
                format!("j{i}")
            };
            let mut rest = Transform::IDENTITY;
            if i > 0 {
                rest.translation = Vec3::new(0.0, 1.0, 0.0);
            }
            if i == 1 {
                rest.rotation = Quat::from_rotation_z(0.1);
            }
            Joint {
                name,
                parent: (i > 0).then(|| JointIndex(i as u32 - 1)),
                rest_local: rest,
            }
        })
        .collect();
    Skeleton::new(joints).expect("valid chain")
}

/// A cylinder of radius 0.3 from y = 0 to y = `height`, 200 vertices, no normals (the
/// exporter computes them), UVs, two morph targets (`bulge` with normal deltas, `pinch`
/// without).
pub(crate) fn cylinder(height: f32) -> Mesh {
    let mut positions = Vec::new();
    let mut uvs = Vec::new();
    let mut bulge = Vec::new();
    let mut bulge_normals = Vec::new();
    let mut pinch = Vec::new();
    for r in 0..RINGS {
        let v = r as f32 / (RINGS - 1) as f32;
        for s in 0..SEGMENTS {
            let u = s as f32 / SEGMENTS as f32;
            let a = u * std::f32::consts::TAU;
            let radial = Vec3::new(a.cos(), 0.0, a.sin());
            positions.push(radial * 0.3 + Vec3::Y * (v * height));
            uvs.push(Vec2::new(u, 1.0 - v));
            let amount = (v * std::f32::consts::PI).sin();
            bulge.push(radial * 0.2 * amount);
            bulge_normals.push(Vec3::new(0.0, 0.1 * amount, 0.0));
            pinch.push(-radial * 0.1 * amount + Vec3::Y * 0.05);
        }
    }
    let mut triangles = Vec::new();
    for r in 0..RINGS - 1 {
        for s in 0..SEGMENTS {
            let a = (r * SEGMENTS + s) as u32;
            let b = (r * SEGMENTS + (s + 1) % SEGMENTS) as u32;
            let c = a + SEGMENTS as u32;
            let d = b + SEGMENTS as u32;
            triangles.push([a, c, b]);
            triangles.push([b, c, d]);
        }
    }
    let n = positions.len() as u32;
    Mesh {
        name: "body".into(),
        positions,
        normals: None,
        uvs: Some(uvs),
        triangles,
        source_vertex: (0..n).collect(),
        morph_targets: vec![
            MorphTarget {
                name: "bulge".into(),
                position_deltas: bulge,
                normal_deltas: Some(bulge_normals),
            },
            MorphTarget {
                name: "pinch".into(),
                position_deltas: pinch,
                normal_deltas: None,
            },
        ],
        morph_weights: vec![0.0, 0.25],
        attached_to: None,
        ..Default::default()
    }
}

/// A unit-ish box with flat normals (24 vertices), in the space of `joint`.
pub(crate) fn hat(joint: JointIndex) -> Mesh {
    let mut positions = Vec::new();
    let mut normals = Vec::new();
    let mut triangles = Vec::new();
    for axis in 0..3 {
        for sign in [1.0_f32, -1.0] {
            let mut n = Vec3::ZERO;
            n[axis] = sign;
            let u = Vec3::from_array(std::array::from_fn(|k| f32::from(k == (axis + 1) % 3)));
            let v = n.cross(u);
            let base = positions.len() as u32;
            for (du, dv) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                positions.push((n + u * du + v * dv) * 0.2 + Vec3::Y * 0.3);
                normals.push(n);
            }
            triangles.push([base, base + 1, base + 2]);
            triangles.push([base, base + 2, base + 3]);
        }
    }
    let n = positions.len() as u32;
    Mesh {
        name: "hat".into(),
        positions,
        normals: Some(normals),
        uvs: None,
        triangles,
        source_vertex: (0..n).collect(),
        morph_targets: Vec::new(),
        morph_weights: Vec::new(),
        attached_to: Some(joint),
        ..Default::default()
    }
}

/// Influences for the cylinder's vertices over `palette` (palette entry `k` is chain joint
/// `palette_joint[k]` at height `k`-ish): vertex `v` gets `1 + v % 8` entries.
///
/// With `distinct`, the entries are the nearest distinct joints with a distance falloff;
/// otherwise they cycle over the palette, so short palettes get duplicate entries (merged)
/// and every third row a tiny weight (dropped). Vertex 0 gets no influence at all.
fn cylinder_influences(mesh: &Mesh, heights: &[f32], distinct: bool) -> Influences {
    let rows = mesh.positions.iter().enumerate().map(|(v, p)| {
        if v == 0 {
            return Vec::new();
        }
        let entries = 1 + v % 8;
        let mut order: Vec<usize> = (0..heights.len()).collect();
        order.sort_by(|&a, &b| {
            (heights[a] - p.y)
                .abs()
                .total_cmp(&(heights[b] - p.y).abs())
        });
        let mut row: Vec<Influence> = (0..entries)
            .map(|e| {
                // Fewer joints than entries: the cycle repeats joints (merged by the exporter).
                let k = order[e % order.len()];
                let d = (heights[k] - p.y).abs();
                Influence {
                    joint: k as u32,
                    weight: 1.0 / (1.0 + 3.0 * d * d) + 0.01 * e as f32,
                }
            })
            .collect();
        if !distinct && v % 3 == 0 {
            row.push(Influence {
                joint: order[order.len() - 1] as u32,
                weight: 1e-8,
            });
        }
        row
    });
    Influences::from_rows(rows.collect::<Vec<_>>())
}

/// The inverse model-space rest matrices of `palette`.
fn inverse_binds(skeleton: &Skeleton, palette: &[JointIndex]) -> Vec<Mat4> {
    let model = skeleton.model_rest_matrices();
    palette.iter().map(|j| model[j.get()].inverse()).collect()
}

/// The main test rig: a 3-joint chain, the 200-vertex skinned cylinder with 1–8 raw entries
/// per vertex (duplicates, a tiny weight, one empty row), the hat attached to `tip`, and two
/// clips covering every track kind and interpolation.
///
/// The palette lists the joints tip-first, so palette index 0 is not the skin's root.
pub(crate) fn rig() -> Asset {
    let skeleton = chain(3);
    let body = cylinder(2.0);
    let palette = vec![JointIndex(2), JointIndex(1), JointIndex(0)];
    let heights: Vec<f32> = model_heights(&skeleton, &palette);
    let influences = cylinder_influences(&body, &heights, false);
    let inv_bind = inverse_binds(&skeleton, &palette);
    Asset {
        frame: Default::default(),
        name: "rig".into(),
        skeleton,
        meshes: vec![body, hat(JointIndex(2))],
        skins: vec![SkinBinding {
            method: Default::default(),
            mesh: MeshIndex(0),
            joints: palette,
            inv_bind,
            influences,
        }],
        clips: vec![wave(), idle()],
        meters_per_unit: Some(1.0),
        ik_handles: Vec::new(),
        ..Default::default()
    }
}

/// A 10-joint chain with truly 1–8 distinct influences per vertex (for the second set).
pub(crate) fn wide_rig() -> Asset {
    let skeleton = chain(10);
    let body = cylinder(9.0);
    let palette: Vec<JointIndex> = (0..10).map(JointIndex).collect();
    let heights = model_heights(&skeleton, &palette);
    let influences = cylinder_influences(&body, &heights, true);
    let inv_bind = inverse_binds(&skeleton, &palette);
    Asset {
        frame: Default::default(),
        name: "wide".into(),
        skeleton,
        meshes: vec![body],
        skins: vec![SkinBinding {
            method: Default::default(),
            mesh: MeshIndex(0),
            joints: palette,
            inv_bind,
            influences,
        }],
        clips: Vec::new(),
        meters_per_unit: None,
        ik_handles: Vec::new(),
        ..Default::default()
    }
}

/// Two separate skeleton trees (`left` and `right` roots, one child each) skinning one mesh:
/// the palette has no common ancestor, so the exporter adds `rigport_root`.
pub(crate) fn two_roots() -> Asset {
    let joint = |name: &str, parent: Option<u32>, x: f32| Joint {
        name: name.into(),
        parent: parent.map(JointIndex),
        rest_local: Transform::from_translation(if parent.is_some() {
            Vec3::Y
        } else {
            Vec3::X * x
        }),
    };
    let skeleton = Skeleton::new(vec![
        joint("left", None, -1.0),
        joint("left_end", Some(0), 0.0),
        joint("right", None, 1.0),
        joint("right_end", Some(2), 0.0),
    ])
    .expect("valid skeleton");
    let body = cylinder(1.0);
    let palette = vec![JointIndex(1), JointIndex(3)];
    let influences = Influences::from_rows(body.positions.iter().map(|p| {
        let right = (p.x * 0.5 + 0.5).clamp(0.0, 1.0);
        [
            Influence {
                joint: 0,
                weight: 1.0 - right,
            },
            Influence {
                joint: 1,
                weight: right,
            },
        ]
    }));
    let inv_bind = inverse_binds(&skeleton, &palette);
    Asset {
        frame: Default::default(),
        name: "two_roots".into(),
        skeleton,
        meshes: vec![body],
        skins: vec![SkinBinding {
            method: Default::default(),
            mesh: MeshIndex(0),
            joints: palette,
            inv_bind,
            influences,
        }],
        clips: vec![Clip {
            name: "sway".into(),
            tracks: vec![Track {
                target: TrackTarget::Rotation(JointIndex(2)),
                interpolation: Interpolation::Linear,
                times: vec![0.0, 1.0],
                values: [Quat::IDENTITY, Quat::from_rotation_z(0.5)]
                    .iter()
                    .flat_map(|q| q.to_array())
                    .collect(),
            }],
        }],
        meters_per_unit: None,
        ik_handles: Vec::new(),
        ..Default::default()
    }
}

/// A star of 300 joints (one root, 299 children) skinning a small strip: palette indices
/// above 255 force `UNSIGNED_SHORT` joints.
pub(crate) fn big_palette() -> Asset {
    let n = 300;
    let joints = (0..n)
        .map(|i| Joint {
            name: format!("b{i}"),
            parent: (i > 0).then_some(JointIndex(0)),
            rest_local: Transform::from_translation(Vec3::new(i as f32 * 0.01, 0.0, 0.0)),
        })
        .collect();
    let skeleton = Skeleton::new(joints).expect("valid skeleton");
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    for k in 0..40_u32 {
        positions.push(Vec3::new(k as f32 * 0.1, 0.0, 0.0));
        positions.push(Vec3::new(k as f32 * 0.1, 0.1, 0.0));
        if k > 0 {
            let (a, b, c, d) = (2 * k - 2, 2 * k - 1, 2 * k, 2 * k + 1);
            triangles.push([a, c, b]);
            triangles.push([b, c, d]);
        }
    }
    let count = positions.len() as u32;
    let palette: Vec<JointIndex> = (0..n as u32)
        .collect::<Vec<_>>()
        .into_iter()
        .map(JointIndex)
        .collect();
    let influences = Influences::from_rows((0..count).map(|v| {
        [
            Influence {
                joint: 299 - v,
                weight: 0.75,
            },
            Influence {
                joint: v * 7 % 300,
                weight: 0.25,
            },
        ]
    }));
    let inv_bind = inverse_binds(&skeleton, &palette);
    Asset {
        frame: Default::default(),
        name: "big_palette".into(),
        skeleton,
        meshes: vec![Mesh {
            name: "strip".into(),
            positions,
            triangles,
            source_vertex: (0..count).collect(),
            ..Default::default()
        }],
        skins: vec![SkinBinding {
            method: Default::default(),
            mesh: MeshIndex(0),
            joints: palette,
            inv_bind,
            influences,
        }],
        clips: Vec::new(),
        meters_per_unit: None,
        ik_handles: Vec::new(),
        ..Default::default()
    }
}

/// Model-space rest heights (y) of the palette joints.
fn model_heights(skeleton: &Skeleton, palette: &[JointIndex]) -> Vec<f32> {
    let model = skeleton.model_rest_matrices();
    palette.iter().map(|j| model[j.get()].w_axis.y).collect()
}

/// Flat xyzw floats of quaternions.
fn quats(qs: &[Quat]) -> Vec<f32> {
    qs.iter().flat_map(|q| q.to_array()).collect()
}

/// Clip `wave`: LINEAR translation, LINEAR rotation with a sign flip and non-unit keys,
/// STEP scale (same times as the translation), CUBICSPLINE rotation, LINEAR morph weights.
fn wave() -> Clip {
    let times3 = vec![0.0, 0.5, 1.0];
    let q1 = Quat::from_rotation_z(0.4);
    let q2 = Quat::from_rotation_z(0.8);
    let q3 = Quat::from_rotation_x(0.3) * Quat::from_rotation_z(0.6);
    Clip {
        name: "wave".into(),
        tracks: vec![
            Track {
                target: TrackTarget::Translation(JointIndex(0)),
                interpolation: Interpolation::Linear,
                times: times3.clone(),
                values: vec![0.0, 0.0, 0.0, 0.1, 0.2, 0.0, 0.0, 0.0, 0.3],
            },
            Track {
                target: TrackTarget::Rotation(JointIndex(1)),
                interpolation: Interpolation::Linear,
                times: vec![0.0, 0.5, 1.0, 1.5],
                // Key 2 stored with the opposite sign, key 3 at twice unit length.
                values: quats(&[Quat::from_rotation_z(0.1), q1, -q2, q3 * 2.0]),
            },
            Track {
                target: TrackTarget::Scale(JointIndex(2)),
                interpolation: Interpolation::Step,
                times: times3.clone(),
                values: vec![1.0, 1.0, 1.0, 1.2, 0.9, 1.2, 1.0, 1.0, 1.0],
            },
            Track {
                target: TrackTarget::Rotation(JointIndex(2)),
                interpolation: Interpolation::CubicSpline,
                times: vec![0.0, 1.0, 2.0],
                values: [
                    [0.0, 0.0, 0.0, 0.0],
                    Quat::IDENTITY.to_array(),
                    [0.0, 0.0, 0.2, 0.0],
                    [0.0, 0.0, 0.2, 0.0],
                    (-q1).to_array(),
                    [0.0, 0.0, 0.1, 0.0],
                    [0.0, 0.0, 0.1, 0.0],
                    q2.to_array(),
                    [0.0, 0.0, 0.0, 0.0],
                ]
                .concat(),
            },
            Track {
                target: TrackTarget::MorphWeights(MeshIndex(0)),
                interpolation: Interpolation::Linear,
                times: times3,
                values: vec![0.0, 0.0, 1.0, 0.5, 0.0, 1.0],
            },
        ],
    }
}

/// Clip `idle`: CUBICSPLINE translation and morph weights, and a one-key STEP rotation.
fn idle() -> Clip {
    Clip {
        name: "idle".into(),
        tracks: vec![
            Track {
                target: TrackTarget::Translation(JointIndex(1)),
                interpolation: Interpolation::CubicSpline,
                times: vec![0.0, 2.0],
                values: vec![
                    0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.1, 0.0, 0.0, //
                    -0.1, 0.0, 0.0, 0.0, 1.1, 0.0, 0.0, 0.0, 0.0,
                ],
            },
            Track {
                target: TrackTarget::MorphWeights(MeshIndex(0)),
                interpolation: Interpolation::CubicSpline,
                times: vec![0.0, 2.0],
                values: vec![0.0, 0.0, 0.0, 0.0, 0.5, 0.5, 0.0, 0.0, 0.0, 0.0, 0.5, 0.5],
            },
            Track {
                target: TrackTarget::Rotation(JointIndex(0)),
                interpolation: Interpolation::Step,
                times: vec![0.0],
                values: Quat::from_rotation_y(0.2).to_array().to_vec(),
            },
        ],
    }
}

/// Unskinned meshes only: a 265 × 265 grid (70 225 vertices, so `UNSIGNED_INT` indices) at
/// the scene root and the hat, unattached, with a morph target and a clip animating it.
pub(crate) fn static_props() -> Asset {
    let side = 265_u32;
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    for z in 0..side {
        for x in 0..side {
            positions.push(Vec3::new(
                x as f32 * 0.01,
                ((x + z) as f32 * 0.1).sin() * 0.02,
                z as f32 * 0.01,
            ));
            if x > 0 && z > 0 {
                let (a, b, c, d) = (
                    (z - 1) * side + x - 1,
                    (z - 1) * side + x,
                    z * side + x - 1,
                    z * side + x,
                );
                triangles.push([a, c, b]);
                triangles.push([b, c, d]);
            }
        }
    }
    let count = positions.len() as u32;
    let grid = Mesh {
        name: "grid".into(),
        positions,
        triangles,
        source_vertex: (0..count).collect(),
        ..Default::default()
    };
    let mut hat = hat(JointIndex(0));
    hat.attached_to = None;
    hat.morph_targets.push(MorphTarget {
        name: "squash".into(),
        position_deltas: hat
            .positions
            .iter()
            .map(|p| Vec3::new(0.0, -0.5 * p.y, 0.0))
            .collect(),
        normal_deltas: None,
    });
    Asset {
        frame: Default::default(),
        name: "props".into(),
        skeleton: Skeleton::default(),
        meshes: vec![grid, hat],
        skins: Vec::new(),
        clips: vec![Clip {
            name: "squash".into(),
            tracks: vec![Track {
                target: TrackTarget::MorphWeights(MeshIndex(1)),
                interpolation: Interpolation::Step,
                times: vec![0.0, 0.25, 0.5],
                values: vec![0.0, 1.0, 0.0],
            }],
        }],
        meters_per_unit: None,
        ik_handles: Vec::new(),
        ..Default::default()
    }
}

/// A skeleton and nothing else: no binary data at all.
pub(crate) fn bones_only() -> Asset {
    Asset {
        name: "bones".into(),
        skeleton: chain(3),
        ..Default::default()
    }
}
