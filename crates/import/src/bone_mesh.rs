//! A generated bone mesh: one small skinned shape per bone, so skeleton-only inputs show
//! their motion.
//!
//! Motion-capture formats (BVH, ASF/AMC) carry a skeleton and no geometry, and most glTF
//! viewers draw nothing for a skin-less node hierarchy. [`bone_mesh`] builds the shape
//! Blender draws for a bone in its "octahedral" display: a double pyramid from the parent
//! joint to the child joint, widest at a tenth of its length.
//!
//! A joint whose own translation is animated (root motion: a Bandai Namco BVH's hips under
//! a floor-level root) is not held at a fixed distance from its parent, so [`add_bone_mesh`]
//! gives it no shape from its parent: a rigid one would be a wedge from the floor to the
//! hips in every frame ([`moving_joints`]).

use glam::{Mat4, Vec3};
use rigport_model::{
    Asset, Influence, Influences, JointIndex, Mesh, MeshIndex, Skeleton, SkinBinding,
};

/// Where along the bone the waist sits, as a fraction of its length (Blender's octahedral
/// bone display).
const WAIST_AT: f32 = 0.1;
/// The waist's radius, as a fraction of the bone's length.
const WAIST_RADIUS: f32 = 0.1;
/// Bones shorter than this fraction of the skeleton's rest size (its extent or its distance
/// from the origin, whichever is larger) get no shape: their waist would be within a few
/// hundred `f32` ulps of the axis, and their triangles close to degenerate.
const MIN_RELATIVE_LENGTH: f32 = 1e-4;
/// Vertices per bone shape: 8 triangles with their own 3 vertices (flat shading).
pub const VERTICES_PER_BONE: usize = 24;
/// Triangles per bone shape.
pub const TRIANGLES_PER_BONE: usize = 8;

/// One small skinned shape per bone (parent joint -> child joint), rigidly bound to the
/// parent joint, so a viewer shows the motion of a skeleton-only asset.
///
/// A bone is a joint with a parent whose rest model-space position differs from the
/// parent's. Shapes come in joint order of the child joint, [`VERTICES_PER_BONE`] vertices
/// and [`TRIANGLES_PER_BONE`] triangles each: the four triangles from the base (the parent
/// joint) to the waist, then the four from the waist to the tip (the child joint). Every
/// triangle has its own vertices with its unit face normal (flat shading) and winds
/// counter-clockwise seen from outside (glTF's front face).
///
/// Positions are model-space rest positions (the bind pose); each vertex has one influence,
/// weight 1, on the bone's parent joint. The binding's palette holds only the joints used,
/// in joint order, with `inv_bind` the inverse of each joint's rest model matrix
/// ([`Skeleton::model_rest_matrices`]). The mesh is named `bones`; `source_vertex` is the
/// identity. The binding's `mesh` is [`MeshIndex`] 0: callers adding the mesh elsewhere set
/// it (see [`add_bone_mesh`]).
///
/// `None` when no bone has a non-zero length (or every such bone's parent has a singular
/// rest matrix, which no inverse bind matrix can undo).
pub fn bone_mesh(skeleton: &Skeleton) -> Option<(Mesh, SkinBinding)> {
    bone_mesh_except(skeleton, &[])
}

/// As [`bone_mesh`], without the bones that end at a joint `k` with `skip[k]` (indices past
/// the end of `skip` are kept).
pub fn bone_mesh_except(skeleton: &Skeleton, skip: &[bool]) -> Option<(Mesh, SkinBinding)> {
    let model = skeleton.model_rest_matrices();
    let heads: Vec<Vec3> = model.iter().map(|m| m.w_axis.truncate()).collect();
    let extent = heads
        .iter()
        .fold(None, |acc: Option<(Vec3, Vec3)>, p| {
            Some(acc.map_or((*p, *p), |(lo, hi)| (lo.min(*p), hi.max(*p))))
        })
        .map_or(0.0, |(lo, hi)| {
            (hi - lo).length().max(lo.length()).max(hi.length())
        });
    let min_length = extent * MIN_RELATIVE_LENGTH;
    // Palette slot per joint, assigned in joint order after the bones are known.
    let mut inv_bind_of: Vec<Option<Mat4>> = vec![None; skeleton.len()];
    let mut bones: Vec<(usize, Vec3, Vec3)> = Vec::new();
    for (child, joint) in skeleton.joints().iter().enumerate() {
        let Some(parent) = joint.parent.map(JointIndex::get) else {
            continue;
        };
        if skip.get(child).copied().unwrap_or(false) {
            continue;
        }
        let (Some(&head), Some(&tail), Some(parent_model)) =
            (heads.get(parent), heads.get(child), model.get(parent))
        else {
            continue;
        };
        let length = head.distance(tail);
        if length <= min_length {
            continue;
        }
        let inv = parent_model.inverse();
        if parent_model.determinant() == 0.0 || !inv.is_finite() {
            continue;
        }
        if let Some(slot) = inv_bind_of.get_mut(parent) {
            *slot = Some(inv);
        }
        bones.push((parent, head, tail));
    }
    if bones.is_empty() {
        return None;
    }
    let mut palette_slot = vec![u32::MAX; skeleton.len()];
    let mut joints = Vec::new();
    let mut inv_bind = Vec::new();
    for (j, inv) in inv_bind_of.iter().enumerate() {
        if let Some(inv) = inv {
            palette_slot[j] = joints.len() as u32;
            joints.push(JointIndex(j as u32));
            inv_bind.push(*inv);
        }
    }

    let mut positions = Vec::with_capacity(bones.len() * VERTICES_PER_BONE);
    let mut normals = Vec::with_capacity(positions.capacity());
    let mut rows = Vec::with_capacity(positions.capacity());
    for &(parent, head, tail) in &bones {
        let axis = tail - head;
        let length = axis.length();
        let dir = axis / length;
        // u, v, dir right-handed (u × v = dir), so the waist ring runs counter-clockwise
        // about the bone.
        let u = dir.any_orthonormal_vector();
        let v = dir.cross(u);
        let waist = head + axis * WAIST_AT;
        let r = length * WAIST_RADIUS;
        let ring = [waist + u * r, waist + v * r, waist - u * r, waist - v * r];
        let mut tri = |a: Vec3, b: Vec3, c: Vec3| {
            let n = (b - a).cross(c - a).normalize_or(dir);
            positions.extend([a, b, c]);
            normals.extend([n; 3]);
        };
        // Base (head) fan winds opposite to the tip fan so both face outwards.
        for i in 0..4 {
            tri(ring[(i + 1) % 4], ring[i], head);
        }
        for i in 0..4 {
            tri(ring[i], ring[(i + 1) % 4], tail);
        }
        let joint = palette_slot.get(parent).copied().unwrap_or(0);
        rows.extend(std::iter::repeat_n(
            [Influence { joint, weight: 1.0 }],
            VERTICES_PER_BONE,
        ));
    }
    let count = positions.len() as u32;
    let mesh = Mesh {
        name: "bones".into(),
        positions,
        normals: Some(normals),
        uvs: None,
        triangles: (0..count / 3)
            .map(|t| [3 * t, 3 * t + 1, 3 * t + 2])
            .collect(),
        source_vertex: (0..count).collect(),
        morph_targets: Vec::new(),
        morph_weights: Vec::new(),
        attached_to: None,
        ..Default::default()
    };
    let skin = SkinBinding {
        method: Default::default(),
        mesh: MeshIndex(0),
        joints,
        inv_bind,
        influences: Influences::from_rows(rows),
    };
    Some((mesh, skin))
}

/// Per joint: whether some clip moves its own translation, i.e. a translation track whose
/// keys differ from its first key by more than the tolerance that makes a bone too short to
/// draw (the skeleton's rest size times 1e-4). Constant translation channels (a Bandai
/// Namco BVH gives every joint position channels that repeat the offset) do not count.
pub fn moving_joints(asset: &Asset) -> Vec<bool> {
    let skeleton = &asset.skeleton;
    let heads: Vec<Vec3> = skeleton
        .model_rest_matrices()
        .iter()
        .map(|m| m.w_axis.truncate())
        .collect();
    let (lo, hi) = heads.iter().fold(
        (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    );
    let extent = if heads.is_empty() {
        0.0
    } else {
        (hi - lo).length().max(lo.length()).max(hi.length())
    };
    let tolerance = extent * MIN_RELATIVE_LENGTH;
    let mut moving = vec![false; skeleton.len()];
    for clip in &asset.clips {
        for track in &clip.tracks {
            let rigport_model::TrackTarget::Translation(j) = track.target else {
                continue;
            };
            // Cubic-spline keys hold (in-tangent, value, out-tangent).
            let (stride, offset) = match track.interpolation {
                rigport_model::Interpolation::CubicSpline => (9, 3),
                _ => (3, 0),
            };
            let key = |k: usize| {
                let at = k * stride + offset;
                track
                    .values
                    .get(at..at + 3)
                    .map(|v| Vec3::new(v[0], v[1], v[2]))
            };
            let Some(first) = key(0) else {
                continue;
            };
            let moves = (1..track.times.len())
                .filter_map(key)
                .any(|v| v.distance(first) > tolerance);
            if let (true, Some(slot)) = (moves, moving.get_mut(j.get())) {
                *slot = true;
            }
        }
    }
    moving
}

/// Adds the bone mesh to an asset that has no meshes; false if it already has one or the
/// skeleton has no bone of non-zero length. Joints whose translation is animated
/// ([`moving_joints`]) get no bone from their parent.
///
/// The mesh is appended with its skin binding (pointing at it); nothing else changes.
pub fn add_bone_mesh(asset: &mut Asset) -> bool {
    if !asset.meshes.is_empty() {
        return false;
    }
    let skip = moving_joints(asset);
    let Some((mesh, mut skin)) = bone_mesh_except(&asset.skeleton, &skip) else {
        return false;
    };
    skin.mesh = MeshIndex(asset.meshes.len() as u32);
    asset.meshes.push(mesh);
    asset.skins.push(skin);
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Quat;
    use rigport_eval::{Pose, Rig, RigOutput};
    use rigport_model::{Joint, Transform};

    /// A small branching skeleton: hips -> spine -> head, hips -> leg -> foot, a zero-length
    /// `foot_end` under `foot`, rest rotations and a non-unit scale on `spine`.
    fn skeleton() -> Skeleton {
        let joint = |name: &str, parent: Option<u32>, t: Vec3, r: Quat, s: f32| Joint {
            name: name.into(),
            parent: parent.map(JointIndex),
            rest_local: Transform {
                translation: t,
                rotation: r,
                scale: Vec3::splat(s),
            },
        };
        Skeleton::new(vec![
            joint(
                "hips",
                None,
                Vec3::new(0.5, 1.0, -0.2),
                Quat::from_rotation_y(0.4),
                1.0,
            ),
            joint(
                "spine",
                Some(0),
                Vec3::new(0.0, 0.3, 0.05),
                Quat::from_rotation_x(0.2),
                1.5,
            ),
            joint(
                "head",
                Some(1),
                Vec3::new(0.0, 0.4, 0.0),
                Quat::IDENTITY,
                1.0,
            ),
            joint(
                "leg",
                Some(0),
                Vec3::new(0.1, -0.1, 0.0),
                Quat::from_rotation_z(-0.3),
                1.0,
            ),
            joint(
                "foot",
                Some(3),
                Vec3::new(0.0, -0.8, 0.0),
                Quat::IDENTITY,
                1.0,
            ),
            joint("foot_end", Some(4), Vec3::ZERO, Quat::IDENTITY, 1.0),
        ])
        .unwrap()
    }

    /// (parent, child) of every bone with a shape, in mesh order.
    const BONES: [(usize, usize); 4] = [(0, 1), (1, 2), (0, 3), (3, 4)];

    fn heads(s: &Skeleton) -> Vec<Vec3> {
        s.model_rest_matrices()
            .iter()
            .map(|m| m.w_axis.truncate())
            .collect()
    }

    #[test]
    fn shapes_lie_on_their_bones_and_face_outwards() {
        let s = skeleton();
        let (mesh, skin) = bone_mesh(&s).unwrap();
        let heads = heads(&s);
        assert_eq!(mesh.name, "bones");
        assert_eq!(mesh.positions.len(), BONES.len() * VERTICES_PER_BONE);
        assert_eq!(mesh.triangles.len(), BONES.len() * TRIANGLES_PER_BONE);
        assert_eq!(mesh.source_vertex, (0..96).collect::<Vec<u32>>());
        let normals = mesh.normals.as_ref().unwrap();
        for (b, &(parent, child)) in BONES.iter().enumerate() {
            let (head, tail) = (heads[parent], heads[child]);
            let length = head.distance(tail);
            let dir = (tail - head) / length;
            let verts = &mesh.positions[b * VERTICES_PER_BONE..(b + 1) * VERTICES_PER_BONE];
            // On the hull: within the double cone from head to tail, widest (0.1 L) at 0.1 L.
            for p in verts {
                let along = (*p - head).dot(dir);
                let radial = (*p - head - dir * along).length();
                assert!((-1e-5..=length + 1e-5).contains(&along), "bone {b}: {p}");
                let profile = if along < 0.1 * length {
                    along
                } else {
                    0.1 * length * (length - along) / (0.9 * length)
                };
                assert!(radial <= profile + 1e-5, "bone {b}: {p} off the hull");
            }
            assert!(
                verts.iter().any(|p| p.distance(head) < 1e-6),
                "base at the parent"
            );
            assert!(
                verts.iter().any(|p| p.distance(tail) < 1e-6),
                "tip at the child"
            );
            assert!(
                verts
                    .iter()
                    .any(|p| ((*p - head).dot(dir) - 0.1 * length).abs() < 1e-5
                        && p.distance(head + dir * 0.1 * length) > 0.1 * length - 1e-5),
                "waist of radius 0.1 L at 0.1 L"
            );
            // Outward winding: positive signed volume, equal to the octahedron's
            // (1/3 * waist square area 2r^2 * length).
            let tris = &mesh.triangles[b * TRIANGLES_PER_BONE..(b + 1) * TRIANGLES_PER_BONE];
            let mut volume = 0.0;
            for t in tris {
                let [a, bb, c] = t.map(|i| mesh.positions[i as usize]);
                volume += a.dot(bb.cross(c)) / 6.0;
                let cross = (bb - a).cross(c - a);
                assert!(
                    cross.length() > 1e-4 * length * length,
                    "bone {b}: degenerate"
                );
                for i in t {
                    let n = normals[*i as usize];
                    assert!((n.length() - 1.0).abs() < 1e-6);
                    assert!(
                        n.dot(cross.normalize()) > 0.9999,
                        "flat normal follows winding"
                    );
                    // Outwards: away from the bone's axis.
                    let centre = (a + bb + c) / 3.0;
                    let along = (centre - head).dot(dir);
                    assert!(n.dot(centre - head - dir * along) > 0.0);
                }
            }
            let r = 0.1 * length;
            let expected = 2.0 * r * r * length / 3.0;
            assert!(
                volume > 0.0 && (volume - expected).abs() < 1e-3 * expected,
                "{volume} vs {expected}"
            );
            // One influence, weight 1, on the parent joint.
            for v in b * VERTICES_PER_BONE..(b + 1) * VERTICES_PER_BONE {
                let row = skin.influences.vertex(v);
                assert_eq!(row.len(), 1);
                assert_eq!(row[0].weight, 1.0);
                assert_eq!(
                    skin.joints[row[0].joint as usize],
                    JointIndex(parent as u32)
                );
            }
        }
        // Only the joints that bones hang from; not `head`, `foot` (zero-length child) or
        // `foot_end`.
        assert_eq!(skin.joints, [JointIndex(0), JointIndex(1), JointIndex(3)]);
    }

    #[test]
    fn binding_is_the_rest_pose_and_follows_the_parent() {
        let s = skeleton();
        let mut asset = Asset {
            name: "bvh".into(),
            skeleton: s.clone(),
            ..Default::default()
        };
        assert!(add_bone_mesh(&mut asset));
        asset.validate().unwrap();
        assert_eq!(asset.skins[0].mesh, MeshIndex(0));
        let rest = s.model_rest_matrices();
        for (j, inv) in asset.skins[0].joints.iter().zip(&asset.skins[0].inv_bind) {
            assert!(
                (*inv * rest[j.get()]).abs_diff_eq(Mat4::IDENTITY, 1e-5),
                "{j}"
            );
        }
        let rig = Rig::new(&asset).unwrap();
        let mut out = RigOutput::default();
        rig.evaluate(&Pose::rest(&s), &mut out).unwrap();
        for (p, q) in out.positions[0].iter().zip(&asset.meshes[0].positions) {
            assert!(p.abs_diff_eq(*q, 1e-5), "{p} vs {q}");
        }
        // Posed: each shape's base follows its parent joint and its tip the child joint.
        let mut pose = Pose::rest(&s);
        pose.rotate_named(&s, "hips", Quat::from_rotation_x(0.7))
            .unwrap();
        pose.rotate_named(&s, "spine", Quat::from_rotation_z(-0.5))
            .unwrap();
        pose.rotate_named(&s, "leg", Quat::from_rotation_y(1.1))
            .unwrap();
        rig.evaluate(&pose, &mut out).unwrap();
        let rest_heads = heads(&s);
        for (b, &(parent, child)) in BONES.iter().enumerate() {
            let verts = b * VERTICES_PER_BONE..(b + 1) * VERTICES_PER_BONE;
            let posed_parent = out.joint_model[parent].w_axis.truncate();
            let posed_child = out.joint_model[child].w_axis.truncate();
            for v in verts {
                let rest_p = asset.meshes[0].positions[v];
                let posed = out.positions[0][v];
                if rest_p.distance(rest_heads[parent]) < 1e-6 {
                    assert!(posed.abs_diff_eq(posed_parent, 1e-5));
                }
                if rest_p.distance(rest_heads[child]) < 1e-6 {
                    assert!(posed.abs_diff_eq(posed_child, 1e-5), "bone {b} tip");
                }
            }
        }
    }

    #[test]
    fn nothing_to_draw_or_already_drawn() {
        let single = Skeleton::new(vec![Joint {
            name: "only".into(),
            parent: None,
            rest_local: Transform::from_translation(Vec3::X),
        }])
        .unwrap();
        assert!(bone_mesh(&single).is_none());
        let stacked = Skeleton::new(vec![
            Joint {
                name: "a".into(),
                parent: None,
                rest_local: Transform::from_translation(Vec3::X),
            },
            Joint {
                name: "b".into(),
                parent: Some(JointIndex(0)),
                rest_local: Transform::IDENTITY,
            },
        ])
        .unwrap();
        let mut asset = Asset {
            skeleton: stacked,
            ..Default::default()
        };
        assert!(!add_bone_mesh(&mut asset), "only a zero-length bone");
        assert!(asset.meshes.is_empty() && asset.skins.is_empty());
        let mut asset = Asset {
            skeleton: skeleton(),
            ..Default::default()
        };
        assert!(add_bone_mesh(&mut asset));
        assert!(!add_bone_mesh(&mut asset), "already has a mesh");
        assert_eq!((asset.meshes.len(), asset.skins.len()), (1, 1));
    }

    #[test]
    fn a_joint_with_animated_translation_gets_no_bone_from_its_parent() {
        use rigport_model::{Clip, Interpolation, Track, TrackTarget};
        // Floor-level root -> hips (root motion) -> spine; every joint has a translation
        // track, only the hips' moves.
        let joint = |name: &str, parent: Option<u32>, t: Vec3| Joint {
            name: name.into(),
            parent: parent.map(JointIndex),
            rest_local: Transform {
                translation: t,
                ..Default::default()
            },
        };
        let skeleton = Skeleton::new(vec![
            joint("root", None, Vec3::ZERO),
            joint("hips", Some(0), Vec3::new(0.0, 90.0, 0.0)),
            joint("spine", Some(1), Vec3::new(0.0, 15.0, 0.0)),
        ])
        .expect("valid");
        let track = |j: u32, values: Vec<f32>| Track {
            target: TrackTarget::Translation(JointIndex(j)),
            interpolation: Interpolation::Linear,
            times: vec![0.0, 1.0],
            values,
        };
        let mut asset = Asset {
            skeleton,
            clips: vec![Clip {
                name: "walk".into(),
                tracks: vec![
                    track(1, vec![0.0, 90.0, 0.0, 1.0, 91.0, 5.0]),
                    track(2, vec![0.0, 15.0, 0.0, 0.0, 15.0, 0.0]),
                ],
            }],
            ..Default::default()
        };
        assert_eq!(moving_joints(&asset), [false, true, false]);
        assert!(add_bone_mesh(&mut asset));
        let mesh = &asset.meshes[0];
        assert_eq!(mesh.vertex_count(), VERTICES_PER_BONE, "only hips -> spine");
        assert_eq!(asset.skins[0].joints, [JointIndex(1)]);
    }
}
