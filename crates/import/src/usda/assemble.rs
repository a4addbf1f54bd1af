//! `Importer::run`: reads the layer metadata, finds the skinnable prims and their
//! skeleton, and assembles the [`Asset`] from the skeleton, the meshes and the clips.

use rigport_model::{Asset, MeshIndex, SceneFrame, Skeleton};

use super::implicit::is_implicit;
use super::importer::Importer;
use super::points::SampledPoints;
use super::root_motion::MovingMesh;
use super::shapes::MeshShapes;
use super::skin::has_skin_primvars;
use crate::ImportError;

impl<'l> Importer<'l, '_> {
    pub(super) fn run(&mut self) -> Result<Asset, ImportError> {
        self.layer_metadata()?;
        let meters_per_unit = self.meters_per_unit()?;
        self.composition_warnings();

        // Skinnable prims and their bindings, in document order.
        let mut skinnable: Vec<(usize, Option<usize>)> = Vec::new();
        for i in 0..self.stage.prims.len() {
            let Some(prim) = self.stage.prims.get(i) else {
                continue;
            };
            if !self.stage.in_scene(i) || !has_skin_primvars(prim) {
                continue;
            }
            if matches!(
                prim.type_name,
                Some("Skeleton" | "SkelAnimation" | "SkelRoot")
            ) {
                continue;
            }
            let under_root = self
                .stage
                .ancestry(i)
                .skip(1)
                .any(|p| p.type_name == Some("SkelRoot"));
            if !under_root {
                let path = prim.path.clone();
                self.incomplete(
                    &path,
                    "has joint influences but no SkelRoot above it: UsdSkel does not skin it, \
                     so it is imported unskinned",
                );
                continue;
            }
            let skel = self.bound_skeleton(i)?;
            skinnable.push((i, Some(skel)));
        }

        // The one skeleton to import.
        let is_mesh = |i: usize| self.stage.prims.get(i).and_then(|p| p.type_name) == Some("Mesh");
        let chosen = match skinnable
            .iter()
            .find(|&&(m, _)| is_mesh(m))
            .or(skinnable.first())
            .and_then(|&(_, s)| s)
        {
            Some(s) => Some(s),
            None => (0..self.stage.prims.len()).find(|&i| {
                self.stage.in_scene(i)
                    && self.stage.prims.get(i).and_then(|p| p.type_name) == Some("Skeleton")
            }),
        };
        let mut others: Vec<(usize, usize)> = Vec::new();
        for &(_, s) in &skinnable {
            if let Some(s) = s.filter(|&s| Some(s) != chosen) {
                match others.iter_mut().find(|(o, _)| *o == s) {
                    Some((_, n)) => *n += 1,
                    None => others.push((s, 1)),
                }
            }
        }
        for (s, n) in others {
            let path = self
                .stage
                .prims
                .get(s)
                .map(|p| p.path.clone())
                .unwrap_or_default();
            self.incomplete(
                &path,
                format!(
                    "a second skeleton, bound by {n} mesh(es): not imported (rigport imports \
                     one skeleton per file, the first one bound); those meshes are left out"
                ),
            );
        }

        let (mut skeleton, skel) = match chosen {
            Some(s) => {
                let (skeleton, data) = self.skeleton(s)?;
                (skeleton, Some((s, data)))
            }
            None => (Skeleton::default(), None),
        };
        let mut root_motion: Option<(usize, String, Vec<String>)> = None;
        if let Some((s, _)) = &skel {
            let (world, animated) = self.world(*s)?;
            self.skel_world = world;
            if !animated.is_empty() {
                // Named after the nearest prim whose transforms move.
                let name = animated
                    .first()
                    .and_then(|p| p.trim_matches(['<', '>']).rsplit('/').next())
                    .unwrap_or("xform")
                    .to_string();
                root_motion = Some((*s, name, animated));
            }
        }

        // Materials (UsdPreviewSurface networks), then meshes.
        let looks = self.materials();
        let mut meshes = Vec::new();
        let mut skins = Vec::new();
        let mut moving = Vec::new();
        let mut sampled = Vec::new();
        for i in 0..self.stage.prims.len() {
            let Some(prim) = self.stage.prims.get(i) else {
                continue;
            };
            if !self.stage.in_scene(i) {
                continue;
            }
            let binding = skinnable.iter().find(|(m, _)| *m == i).map(|&(_, s)| s);
            // Implicit surfaces (Cube, Sphere, Cylinder, Capsule, Cone) are tessellated.
            let is_mesh = prim.type_name == Some("Mesh") || is_implicit(prim.type_name);
            if !is_mesh {
                if binding.is_some() {
                    let (path, ty) = (prim.path.clone(), prim.type_name.unwrap_or("untyped"));
                    self.incomplete(
                        &path,
                        format!(
                            "a skinnable {ty} prim has no surface rigport imports (Meshes and \
                             the implicit Cube, Sphere, Cylinder, Capsule and Cone are): not \
                             imported"
                        ),
                    );
                }
                continue;
            }
            let skin_to = match (binding, &skel) {
                (Some(Some(s)), Some((chosen, data))) if s == *chosen => Some(data),
                (Some(_), _) => continue, // bound to another skeleton: warned above
                (None, _) => None,
            };
            if let Some((mut mesh, skin, channels, animated, samples)) = self.mesh(i, skin_to)? {
                mesh.material = self.stage.prims.get(i).and_then(|p| looks.bound(p));
                let index = MeshIndex(meshes.len() as u32);
                if !channels.is_empty() {
                    self.mesh_shapes.push(MeshShapes {
                        mesh: index,
                        targets: mesh.morph_targets.len(),
                        channels,
                    });
                }
                if let Some(seconds) = samples {
                    sampled.push(SampledPoints {
                        mesh: index,
                        name: mesh.name.clone(),
                        path: self.prim(i).path.clone(),
                        first_target: mesh.morph_targets.len() - seconds.len(),
                        targets: mesh.morph_targets.len(),
                        seconds,
                    });
                }
                meshes.push(mesh);
                if !animated.is_empty() {
                    moving.push(MovingMesh {
                        mesh: index,
                        prim: i,
                        animated,
                    });
                }
                if let Some(mut skin) = skin {
                    skin.mesh = index;
                    skins.push(skin);
                }
            }
        }

        // Clips.
        let mut clips = match &skel {
            Some((s, data)) => self.clips(*s, data)?,
            None => Vec::new(),
        };
        if let Some((s, name, animated)) = root_motion {
            self.root_motion(s, &skeleton, &mut clips, &name)?;
            let path = self.prim(s).path.clone();
            self.note(
                &path,
                format!(
                    "time-sampled transforms (xformOp) on {} are imported as root motion (the \
                     root joints' tracks, sampled at every time code between their samples)",
                    animated.join(", ")
                ),
            );
        }

        self.moving_meshes(&mut skeleton, &mut meshes, &mut clips, &moving)?;
        self.point_sample_tracks(&mut clips, &sampled);

        let asset = Asset {
            frame: SceneFrame {
                up_axis: self.up_axis,
                model_to_scene: self.skel_world,
            },
            name: self
                .path
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default(),
            skeleton,
            meshes,
            skins,
            clips,
            meters_per_unit: Some(meters_per_unit),
            ik_handles: Vec::new(),
            materials: looks.materials,
            images: looks.images,
        };
        crate::check_asset(&asset, || self.file())?;
        Ok(asset)
    }

    // -----------------------------------------------------------------------------------
    // Layer
    // -----------------------------------------------------------------------------------
}
