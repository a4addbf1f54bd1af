//! Test-only glTF reading and skinning, independent of rigport: the `gltf` crate reads the
//! file, and the skinning is written here from the glTF spec (§3.7.3).

use std::collections::HashMap;
use std::path::Path;

use rigport_model::glam::{Mat4, Quat, Vec3};

/// A glTF file's scene, as plain data.
pub struct GltfScene {
    pub node_names: Vec<String>,
    pub parents: Vec<Option<usize>>,
    /// Local TRS per node: (translation, rotation, scale).
    pub local: Vec<(Vec3, Quat, Vec3)>,
    pub skins: Vec<GltfSkin>,
    pub animations: Vec<GltfAnimation>,
}

/// One skinned primitive.
pub struct GltfSkin {
    pub joints: Vec<usize>,
    pub inverse_bind: Vec<Mat4>,
    pub positions: Vec<Vec3>,
    /// Per vertex: (node index, weight) with weight > 0, from every JOINTS_n/WEIGHTS_n set.
    pub influences: Vec<Vec<(usize, f32)>>,
}

/// One animation channel, flattened.
pub struct GltfChannel {
    pub node: usize,
    pub path: String,
    pub interpolation: String,
    pub times: Vec<f32>,
    pub values: Vec<Vec<f32>>,
}

/// One animation.
pub struct GltfAnimation {
    pub name: String,
    pub channels: Vec<GltfChannel>,
}

pub fn read(path: &Path) -> GltfScene {
    let (doc, buffers, _) =
        gltf::import(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let n = doc.nodes().len();
    let mut parents = vec![None; n];
    for node in doc.nodes() {
        for c in node.children() {
            parents[c.index()] = Some(node.index());
        }
    }
    let local = doc
        .nodes()
        .map(|node| {
            let (t, r, s) = node.transform().decomposed();
            (Vec3::from(t), Quat::from_array(r), Vec3::from(s))
        })
        .collect();
    let node_names = doc
        .nodes()
        .map(|n| n.name().unwrap_or("").to_string())
        .collect();
    let mut skins = Vec::new();
    for node in doc.nodes() {
        let (Some(mesh), Some(skin)) = (node.mesh(), node.skin()) else {
            continue;
        };
        let joints: Vec<usize> = skin.joints().map(|j| j.index()).collect();
        let inverse_bind: Vec<Mat4> = skin
            .reader(|b| Some(&buffers[b.index()]))
            .read_inverse_bind_matrices()
            .map(|it| it.map(|m| Mat4::from_cols_array_2d(&m)).collect())
            .unwrap_or_else(|| vec![Mat4::IDENTITY; joints.len()]);
        for prim in mesh.primitives() {
            let reader = prim.reader(|b| Some(&buffers[b.index()]));
            let positions: Vec<Vec3> = reader
                .read_positions()
                .expect("positions")
                .map(Vec3::from)
                .collect();
            let mut influences = vec![Vec::new(); positions.len()];
            let mut set = 0;
            while let (Some(js), Some(ws)) = (reader.read_joints(set), reader.read_weights(set)) {
                for (v, (j, w)) in js.into_u16().zip(ws.into_f32()).enumerate() {
                    for k in 0..4 {
                        if w[k] > 0.0 {
                            influences[v].push((joints[j[k] as usize], w[k]));
                        }
                    }
                }
                set += 1;
            }
            skins.push(GltfSkin {
                joints: joints.clone(),
                inverse_bind: inverse_bind.clone(),
                positions,
                influences,
            });
        }
    }
    let animations = doc
        .animations()
        .map(|a| GltfAnimation {
            name: a.name().unwrap_or("").to_string(),
            channels: a
                .channels()
                .map(|ch| {
                    let reader = ch.reader(|b| Some(&buffers[b.index()]));
                    let times: Vec<f32> = reader.read_inputs().expect("inputs").collect();
                    use gltf::animation::util::ReadOutputs;
                    let values: Vec<Vec<f32>> = match reader.read_outputs().expect("outputs") {
                        ReadOutputs::Translations(it) => it.map(|v| v.to_vec()).collect(),
                        ReadOutputs::Scales(it) => it.map(|v| v.to_vec()).collect(),
                        ReadOutputs::Rotations(r) => r.into_f32().map(|v| v.to_vec()).collect(),
                        ReadOutputs::MorphTargetWeights(w) => {
                            let all: Vec<f32> = w.into_f32().collect();
                            let per = all.len() / times.len().max(1);
                            all.chunks(per.max(1)).map(|c| c.to_vec()).collect()
                        }
                    };
                    GltfChannel {
                        node: ch.target().node().index(),
                        path: format!("{:?}", ch.target().property()),
                        interpolation: format!("{:?}", ch.sampler().interpolation()),
                        times,
                        values,
                    }
                })
                .collect(),
        })
        .collect();
    GltfScene {
        node_names,
        parents,
        local,
        skins,
        animations,
    }
}

impl GltfScene {
    pub fn node_by_name(&self) -> HashMap<&str, usize> {
        self.node_names
            .iter()
            .enumerate()
            .map(|(i, n)| (n.as_str(), i))
            .collect()
    }

    /// World matrices with per-node local rotation changes (`local = rest * delta`).
    pub fn world(&self, deltas: &HashMap<usize, Quat>) -> Vec<Mat4> {
        fn rec(
            s: &GltfScene,
            d: &HashMap<usize, Quat>,
            i: usize,
            memo: &mut Vec<Option<Mat4>>,
        ) -> Mat4 {
            if let Some(m) = memo[i] {
                return m;
            }
            let (t, r, sc) = s.local[i];
            let r = d.get(&i).map_or(r, |q| r * *q);
            let local = Mat4::from_scale_rotation_translation(sc, r, t);
            let m = match s.parents[i] {
                Some(p) => rec(s, d, p, memo) * local,
                None => local,
            };
            memo[i] = Some(m);
            m
        }
        let mut memo = vec![None; self.local.len()];
        (0..self.local.len())
            .map(|i| rec(self, deltas, i, &mut memo))
            .collect()
    }

    /// Linear blend skinning of skin `s` for the given node world matrices (glTF §3.7.3).
    pub fn skin_positions(&self, s: usize, world: &[Mat4]) -> Vec<Vec3> {
        let skin = &self.skins[s];
        let ibm: HashMap<usize, Mat4> = skin
            .joints
            .iter()
            .zip(&skin.inverse_bind)
            .map(|(j, m)| (*j, *m))
            .collect();
        skin.positions
            .iter()
            .zip(&skin.influences)
            .map(|(p, infl)| {
                let mut m = Mat4::ZERO;
                for (node, w) in infl {
                    m += (world[*node] * ibm[node]) * *w;
                }
                m.transform_point3(*p)
            })
            .collect()
    }
}
