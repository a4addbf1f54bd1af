use crate::{
    Clip, Image, Interpolation, JointIndex, Material, Mesh, SceneFrame, Skeleton, SkinBinding,
    TrackTarget,
};

/// Everything rigport knows about one rig: skeleton, meshes, skin bindings and clips.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Asset {
    /// Name, usually the source file's stem.
    pub name: String,
    /// All joints (for glTF sources: every node, so mesh attachments keep their parents).
    pub skeleton: Skeleton,
    /// The meshes.
    pub meshes: Vec<Mesh>,
    /// Skin bindings, at most one per mesh.
    pub skins: Vec<SkinBinding>,
    /// Animation clips.
    pub clips: Vec<Clip>,
    /// Metres per length unit, when the source states it.
    pub meters_per_unit: Option<f64>,
    /// Where the model sits in the source's scene: up axis and the transform of model
    /// space (the skeleton's space) in the scene. Identity and +Y up unless the source
    /// says otherwise.
    pub frame: SceneFrame,
    /// Joints the rig names as inverse-kinematics handles (end effectors), in the source's
    /// order (e.g. CSCI 520 `IKJointIDs`).
    pub ik_handles: Vec<JointIndex>,
    /// Materials, referred to by [`Mesh::material`].
    pub materials: Vec<Material>,
    /// Images, referred to by the materials' textures.
    pub images: Vec<Image>,
}

/// One thing wrong with an [`Asset`], as found by [`Asset::validate`].
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum AssetError {
    /// A mesh attribute's length differs from its position count.
    #[error("mesh {mesh}: {attribute} has {found} entries for {expected} vertices")]
    AttributeLength {
        /// Mesh index.
        mesh: usize,
        /// The attribute.
        attribute: &'static str,
        /// Its length.
        found: usize,
        /// The vertex count.
        expected: usize,
    },
    /// A triangle names a vertex that does not exist.
    #[error("mesh {mesh}: triangle {triangle} names vertex {vertex} of {count}")]
    TriangleIndex {
        /// Mesh index.
        mesh: usize,
        /// Triangle index.
        triangle: usize,
        /// The bad vertex index.
        vertex: u32,
        /// The vertex count.
        count: usize,
    },
    /// A value is NaN or infinite.
    #[error("{what} is not finite")]
    NonFinite {
        /// What holds it.
        what: String,
    },
    /// A reference to a joint, mesh or palette entry is out of range.
    #[error("{what} is out of range")]
    BadReference {
        /// What reference.
        what: String,
    },
    /// A weight is negative.
    #[error("skin {skin}: vertex {vertex} has negative weight {weight}")]
    NegativeWeight {
        /// Skin index.
        skin: usize,
        /// Vertex index.
        vertex: usize,
        /// The weight.
        weight: f32,
    },
    /// A track's key times or value count are inconsistent.
    #[error("clip {clip:?} track {track}: {problem}")]
    BadTrack {
        /// Clip name.
        clip: String,
        /// Track index.
        track: usize,
        /// What is wrong.
        problem: String,
    },
}

/// An asset has no clip of the name asked for: the one "no clip named" error, with the
/// names it has.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("no clip named {name:?}; clips are {}", clip_list(available))]
pub struct NoSuchClip {
    /// The name asked for.
    pub name: String,
    /// The asset's clip names, in order.
    pub available: Vec<String>,
}

fn clip_list(names: &[String]) -> String {
    if names.is_empty() {
        "none".into()
    } else {
        let quoted: Vec<String> = names.iter().map(|n| format!("{n:?}")).collect();
        quoted.join(", ")
    }
}

/// The index in `clips` of the clip named `name`, or of the first clip when `name` is
/// `None` (`Ok(None)` when there is no clip): the one clip lookup, behind [`Asset::clip`].
///
/// # Errors
/// [`NoSuchClip`] when no clip has that name.
pub fn find_clip(clips: &[Clip], name: Option<&str>) -> Result<Option<usize>, NoSuchClip> {
    match name {
        None => Ok((!clips.is_empty()).then_some(0)),
        Some(name) => match clips.iter().position(|c| c.name == name) {
            Some(index) => Ok(Some(index)),
            None => Err(NoSuchClip {
                name: name.to_owned(),
                available: clips.iter().map(|c| c.name.clone()).collect(),
            }),
        },
    }
}

impl Asset {
    /// The index of the clip named `name`, or of the first clip when `name` is `None`
    /// (`Ok(None)` when the asset has no clip).
    ///
    /// # Errors
    /// [`NoSuchClip`] when no clip has that name.
    pub fn clip_index(&self, name: Option<&str>) -> Result<Option<usize>, NoSuchClip> {
        find_clip(&self.clips, name)
    }

    /// The clip named `name`, or the first clip when `name` is `None` (`Ok(None)` when the
    /// asset has no clip).
    ///
    /// # Errors
    /// [`NoSuchClip`] when no clip has that name.
    pub fn clip(&self, name: Option<&str>) -> Result<Option<&Clip>, NoSuchClip> {
        Ok(self.clip_index(name)?.map(|i| &self.clips[i]))
    }

    /// Checks every cross-reference and value; returns every problem found.
    ///
    /// # Errors
    /// The list of problems, in mesh, skin, clip order.
    pub fn validate(&self) -> Result<(), Vec<AssetError>> {
        let mut errs = Vec::new();
        let joint_count = self.skeleton.len();
        for (mi, mesh) in self.meshes.iter().enumerate() {
            let n = mesh.positions.len();
            let mut check_len = |attribute, found| {
                if found != n {
                    errs.push(AssetError::AttributeLength {
                        mesh: mi,
                        attribute,
                        found,
                        expected: n,
                    });
                }
            };
            if let Some(normals) = &mesh.normals {
                check_len("normals", normals.len());
            }
            if let Some(uvs) = &mesh.uvs {
                check_len("uvs", uvs.len());
            }
            for uvs in &mesh.extra_uvs {
                check_len("extra uvs", uvs.len());
            }
            check_len("source_vertex", mesh.source_vertex.len());
            if let Some(m) = mesh.material {
                if m.get() >= self.materials.len() {
                    errs.push(AssetError::BadReference {
                        what: format!("mesh {mi} {m}"),
                    });
                }
            }
            for (ti, target) in mesh.morph_targets.iter().enumerate() {
                if target.position_deltas.len() != n {
                    errs.push(AssetError::AttributeLength {
                        mesh: mi,
                        attribute: "morph target positions",
                        found: target.position_deltas.len(),
                        expected: n,
                    });
                }
                if target.position_deltas.iter().any(|d| !d.is_finite()) {
                    errs.push(AssetError::NonFinite {
                        what: format!("mesh {mi} morph target {ti}"),
                    });
                }
            }
            if mesh.positions.iter().any(|p| !p.is_finite()) {
                errs.push(AssetError::NonFinite {
                    what: format!("mesh {mi} positions"),
                });
            }
            for (ti, tri) in mesh.triangles.iter().enumerate() {
                if let Some(&vertex) = tri.iter().find(|&&v| v as usize >= n) {
                    errs.push(AssetError::TriangleIndex {
                        mesh: mi,
                        triangle: ti,
                        vertex,
                        count: n,
                    });
                    break;
                }
            }
            if let Some(j) = mesh.attached_to {
                if j.get() >= joint_count {
                    errs.push(AssetError::BadReference {
                        what: format!("mesh {mi} attachment {j}"),
                    });
                }
            }
        }
        for (mi, material) in self.materials.iter().enumerate() {
            for (role, texture) in material.textures() {
                if texture.image.get() >= self.images.len() {
                    errs.push(AssetError::BadReference {
                        what: format!("material {mi} {role} texture {}", texture.image),
                    });
                }
            }
            let factors_finite = material.factors().iter().all(|f| f.is_finite());
            if !factors_finite {
                errs.push(AssetError::NonFinite {
                    what: format!("material {mi} factors"),
                });
            }
        }
        for (i, j) in self.ik_handles.iter().enumerate() {
            if j.get() >= joint_count {
                errs.push(AssetError::BadReference {
                    what: format!("IK handle {i} ({j})"),
                });
            }
        }
        for (si, skin) in self.skins.iter().enumerate() {
            let Some(mesh) = self.meshes.get(skin.mesh.get()) else {
                errs.push(AssetError::BadReference {
                    what: format!("skin {si} {}", skin.mesh),
                });
                continue;
            };
            if skin.influences.vertex_count() != mesh.vertex_count() {
                errs.push(AssetError::AttributeLength {
                    mesh: skin.mesh.get(),
                    attribute: "skin influences",
                    found: skin.influences.vertex_count(),
                    expected: mesh.vertex_count(),
                });
            }
            if skin.inv_bind.len() != skin.joints.len() {
                errs.push(AssetError::BadReference {
                    what: format!(
                        "skin {si}: {} inverse bind matrices for {} joints",
                        skin.inv_bind.len(),
                        skin.joints.len()
                    ),
                });
            }
            if skin.inv_bind.iter().any(|m| !m.is_finite()) {
                errs.push(AssetError::NonFinite {
                    what: format!("skin {si} inverse bind matrices"),
                });
            }
            if let Some(j) = skin.joints.iter().find(|j| j.get() >= joint_count) {
                errs.push(AssetError::BadReference {
                    what: format!("skin {si} palette {j}"),
                });
            }
            for (v, row) in skin.influences.rows().enumerate() {
                for inf in row {
                    if inf.joint as usize >= skin.joints.len() {
                        errs.push(AssetError::BadReference {
                            what: format!("skin {si} vertex {v} palette entry {}", inf.joint),
                        });
                    }
                    if !inf.weight.is_finite() {
                        errs.push(AssetError::NonFinite {
                            what: format!("skin {si} vertex {v} weight"),
                        });
                    } else if inf.weight < 0.0 {
                        errs.push(AssetError::NegativeWeight {
                            skin: si,
                            vertex: v,
                            weight: inf.weight,
                        });
                    }
                }
            }
        }
        for clip in &self.clips {
            for (ti, track) in clip.tracks.iter().enumerate() {
                let mut bad = |problem: String| {
                    errs.push(AssetError::BadTrack {
                        clip: clip.name.clone(),
                        track: ti,
                        problem,
                    })
                };
                match track.target {
                    TrackTarget::Translation(j)
                    | TrackTarget::Rotation(j)
                    | TrackTarget::Scale(j)
                        if j.get() >= joint_count =>
                    {
                        bad(format!("targets {j}, which does not exist"))
                    }
                    TrackTarget::MorphWeights(m) if m.get() >= self.meshes.len() => {
                        bad(format!("targets {m}, which does not exist"))
                    }
                    _ => {}
                }
                if track.times.is_empty() {
                    bad("has no keys".into());
                }
                // Branch-free folds rather than `any`: they vectorize, and a valid asset
                // (the usual case) is read to the end either way.
                if !track
                    .times
                    .iter()
                    .fold(true, |ok, &t| ok & (t.is_finite() & (t >= 0.0)))
                {
                    bad("has a negative or non-finite key time".into());
                }
                // `!(b <= a)`, not `b > a`: a NaN pair is not reported here (the check above
                // reports it), as before.
                #[allow(
                    clippy::neg_cmp_op_on_partial_ord,
                    reason = "NaN must compare as before: not increasing is `b <= a`"
                )]
                let increasing = track
                    .times
                    .iter()
                    .zip(track.times.iter().skip(1))
                    .fold(true, |ok, (&a, &b)| ok & !(b <= a));
                if !increasing {
                    bad("key times are not strictly increasing".into());
                }
                let per_key = if track.interpolation == Interpolation::CubicSpline {
                    3
                } else {
                    1
                };
                let c = track.components();
                if c == 0 || track.values.len() != track.times.len() * per_key * c {
                    bad(format!(
                        "{} values for {} keys",
                        track.values.len(),
                        track.times.len()
                    ));
                }
                if !track.values.iter().fold(true, |ok, v| ok & v.is_finite()) {
                    bad("has a non-finite value".into());
                }
            }
        }
        if errs.is_empty() {
            Ok(())
        } else {
            Err(errs)
        }
    }
}
