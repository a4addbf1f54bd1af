//! Cloth on an asset (what `rigport cloth` and the demo's skirt run): take the garment (a mesh of the input
//! by name, or one given), choose its pins, simulate, bake the result into the asset.

use std::fmt;

use rigport_model::{Asset, Mesh, TrackTarget, Warning};

use super::{
    add_garment, simulate, ClothError, ClothOptions, FrameStats, Garment, PinSelection,
    CONTROL_POINTS,
};

/// Where the garment comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum GarmentSource<'a> {
    /// An unskinned mesh of the asset, by name: it is taken out of the asset (and comes
    /// back as the simulated garment).
    Named(&'a str),
    /// A mesh from elsewhere (an OBJ), in the asset's model space.
    Mesh(Box<Mesh>),
}

/// What [`run`] did, for the user.
#[derive(Clone, Debug, PartialEq)]
pub struct ClothReport {
    /// The garment mesh's name.
    pub garment: String,
    /// Simulated particles.
    pub particles: usize,
    /// Pinned particles.
    pub pins: usize,
    /// Collision capsules.
    pub capsules: usize,
    /// Output frames.
    pub frames: usize,
    /// Output frame rate (to a thousandth).
    pub fps: f32,
    /// Substeps per frame.
    pub substeps: u32,
    /// Collision thickness, model units.
    pub thickness: f32,
    /// The body's bounding-box diagonal, model units.
    pub diagonal: f32,
    /// The worst frame measurements.
    pub worst: FrameStats,
    /// Seconds of pre-roll simulated before frame 0.
    pub preroll: f32,
    /// How fast the garment still moved at the end of the pre-roll (units/s;
    /// [`super::Simulation::settle_residual`]).
    pub settle_residual: f32,
    /// The cuts the garment was settled into again ([`super::Cut`]).
    pub cuts: Vec<super::Cut>,
    /// Output frame times, seconds.
    pub times: Vec<f32>,
    /// Every output frame's measurements.
    pub stats: Vec<FrameStats>,
    /// Morph targets written.
    pub targets: usize,
    /// Largest distance between a simulated position and what the targets give.
    pub max_target_error: f32,
}

impl ClothReport {
    /// The frame where `f` is largest, and its value (frame 0, 0 without frames).
    pub fn worst_frame(&self, f: impl Fn(&FrameStats) -> f32) -> (usize, f32) {
        self.stats
            .iter()
            .enumerate()
            .fold((0, 0.0), |a, (i, s)| if f(s) > a.1 { (i, f(s)) } else { a })
    }
}

impl fmt::Display for ClothReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let first = self.stats.first().copied().unwrap_or_default();
        let (fd, depth) = self.worst_frame(|s| s.body_depth);
        let (fi, inside) = self.worst_frame(|s| s.body_inside as f32);
        let touched = self.stats.iter().filter(|s| s.body_inside > 0).count();
        write!(
            f,
            "cloth {:?}: {} particles ({} pinned), {} capsules, {} frames at {} fps x {} substeps after a {} s pre-roll (settle residual {:.3e} units/s; edge stretch {:.2}% at frame 0); max edge stretch {:.2}%, max kinetic energy {:.4} (per unit mass), max vertex speed {:.4} units/s; inside the body surface: {} vertices at most (frame {fi}), on {touched} of {} frames, deepest {:.2e} (frame {fd}; thickness {:.4}); deepest vertex {:.2e} inside a capsule; {} morph targets (max error {:.2e}){}",
            self.garment,
            self.particles,
            self.pins,
            self.capsules,
            self.frames,
            self.fps,
            self.substeps,
            self.preroll,
            self.settle_residual,
            100.0 * first.max_stretch,
            100.0 * self.worst.max_stretch,
            self.worst.kinetic_energy,
            self.worst.max_speed,
            inside as u32,
            self.frames,
            depth,
            self.thickness,
            self.worst.max_depth,
            self.targets,
            self.max_target_error,
            if self.cuts.is_empty() {
                String::new()
            } else {
                let frames: Vec<String> = self.cuts.iter().map(|c| c.frame.to_string()).collect();
                format!("; settled again at the cuts on frames {}", frames.join(", "))
            },
        )
    }
}

/// Removes mesh `index` from `asset`, renumbering the skins and morph-weight tracks of
/// the meshes after it (tracks of the removed mesh are dropped).
fn remove_mesh(asset: &mut Asset, index: usize) -> Mesh {
    let mesh = asset.meshes.remove(index);
    for skin in &mut asset.skins {
        if skin.mesh.get() > index {
            skin.mesh = rigport_model::MeshIndex(skin.mesh.0 - 1);
        }
    }
    for clip in &mut asset.clips {
        clip.tracks.retain(|t| {
            t.target != TrackTarget::MorphWeights(rigport_model::MeshIndex(index as u32))
        });
        for t in &mut clip.tracks {
            if let TrackTarget::MorphWeights(m) = &mut t.target {
                if m.get() > index {
                    *m = rigport_model::MeshIndex(m.0 - 1);
                }
            }
        }
    }
    mesh
}

/// Simulates a garment on `asset` and bakes it in: the garment mesh ends last in
/// `asset.meshes` with one morph target per frame (or `targets` shared ones), the
/// simulated clip gets its weight track and becomes the only clip. Without `pins`, a
/// garment from the input uses its [`CONTROL_POINTS`] values when it has them.
///
/// # Errors
/// [`ClothError::NoGarment`] (no unskinned mesh of that name), the garment and simulation
/// errors of [`Garment::from_mesh`] and [`simulate`].
pub fn run(
    asset: &mut Asset,
    source: GarmentSource<'_>,
    pins: &[PinSelection],
    opts: &ClothOptions<'_>,
    targets: Option<usize>,
    warnings: &mut Vec<Warning>,
    progress: impl FnMut(usize, usize),
) -> Result<ClothReport, ClothError> {
    let mesh = match source {
        GarmentSource::Mesh(m) => *m,
        GarmentSource::Named(name) => {
            let skinned = |i: usize| asset.skins.iter().any(|s| s.mesh.get() == i);
            let index = (0..asset.meshes.len())
                .find(|&i| asset.meshes[i].name == name && !skinned(i))
                .ok_or_else(|| ClothError::NoGarment {
                    name: name.into(),
                    meshes: asset
                        .meshes
                        .iter()
                        .enumerate()
                        .filter(|(i, _)| !skinned(*i))
                        .map(|(_, m)| format!("{:?}", m.name))
                        .collect::<Vec<_>>()
                        .join(", "),
                })?;
            remove_mesh(asset, index)
        }
    };
    let default_pins = [PinSelection::Values(CONTROL_POINTS.into())];
    let pins = if pins.is_empty() && mesh.vertex_values.iter().any(|(n, _)| n == CONTROL_POINTS) {
        &default_pins[..]
    } else {
        pins
    };
    let garment = Garment::from_mesh(asset, &mesh, pins)?;
    let sim = simulate(asset, &garment, opts, warnings, progress)?;
    let name = mesh.name.clone();
    let bake = add_garment(asset, mesh, &sim, targets)?;
    // Keep only the simulated clip: the garment moves with it alone.
    let clip = asset.clips.swap_remove(sim.clip);
    asset.clips = vec![clip];
    let fps = match sim.times.as_slice() {
        // Rounded to a thousandth: frame times are f32, 30 fps would read 29.999998.
        [a, b, ..] if b > a => (1000.0 / (b - a)).round() / 1000.0,
        _ => 0.0,
    };
    Ok(ClothReport {
        garment: name,
        particles: sim.particles,
        pins: sim.pins.len(),
        capsules: sim.capsules.len(),
        frames: sim.times.len(),
        fps,
        substeps: sim.substeps,
        thickness: sim.thickness,
        diagonal: sim.diagonal,
        worst: sim.worst(),
        preroll: sim.preroll,
        settle_residual: sim.settle_residual,
        cuts: sim.cuts.clone(),
        times: sim.times.clone(),
        stats: sim.stats.clone(),
        targets: bake.targets,
        max_target_error: bake.max_error,
    })
}
