//! The demo's garment: a skirt, a flared cone of triangles hanging from the waist, its top
//! ring pinned to the skin (`rigport cloth`, `rigport_deform::cloth`). [`bake`] simulates it
//! on the demo's [`CLIP`] and bakes it into morph targets, as `rigport demo` writes it
//! (`skirt.glb`, `skirt.png`).

use rigport_deform::cloth::asset::{self, ClothReport, GarmentSource};
use rigport_deform::cloth::{ClothOptions, PinSelection};
use rigport_model::glam::Vec3;
use rigport_model::{Asset, Mesh, Warning};

use crate::{Demo, DemoError};

/// The clip the demo's skirt is simulated on: the body bobs down twice while the arm
/// waves; the skirt, made flared, has fallen into its hanging shape during the pre-roll
/// and swings with the body.
pub const CLIP: &str = "wave";

/// Rings of the demo's skirt (waist to hem).
pub const RINGS: u32 = 12;

/// Vertices per ring of the demo's skirt (the first ring's are pinned).
pub const SEGMENTS: u32 = 48;

/// Height of the skirt's waistband, metres (between the hips joint at 0.98 m and the
/// spine at 1.10 m).
pub const WAIST_Y: f32 = 1.0;

/// The skirt's length along its flank, metres (to above the knees).
const LENGTH: f32 = 0.42;

/// How far the hem flares out beyond the waist, metres.
const FLARE: f32 = 0.22;

/// A skirt of `rings` rings of `segments` vertices around the demo body's waist: ring 0
/// (the first `segments` vertices, the ones to pin) lies on the body's cross-section at
/// [`WAIST_Y`] (per direction, the farthest body vertex within 2 cm of that height and 35
/// cm of the axis, so arms do not count), the others flare out (as the square root of
/// the distance down) to the hem. Needs
/// `rings >= 2` and `segments >= 3` (smaller values are raised to them). Triangles are
/// counter-clockwise seen from outside.
///
/// ```
/// let demo = rigport_demo::build(1)?;
/// let skirt = rigport_demo::skirt::skirt(&demo.asset, 10, 40);
/// assert_eq!(skirt.vertex_count(), 400);
/// assert_eq!(skirt.triangles.len(), 2 * 9 * 40);
/// # Ok::<(), rigport_demo::DemoError>(())
/// ```
pub fn skirt(asset: &Asset, rings: u32, segments: u32) -> Mesh {
    let rings = rings.max(2);
    let segments = segments.max(3);
    let body: Vec<Vec3> = asset
        .meshes
        .first()
        .map(|m| {
            m.positions
                .iter()
                .copied()
                .filter(|p| (p.y - WAIST_Y).abs() < 0.02 && p.x.hypot(p.z) < 0.35)
                .collect()
        })
        .unwrap_or_default();
    let mut positions = Vec::with_capacity((rings * segments) as usize);
    // Waist radius per direction: the farthest slab vertex within 10 degrees of it.
    let radius: Vec<f32> = (0..segments)
        .map(|s| {
            let a = std::f32::consts::TAU * s as f32 / segments as f32;
            let dir = Vec3::new(a.cos(), 0.0, a.sin());
            body.iter()
                .filter(|p| Vec3::new(p.x, 0.0, p.z).normalize_or_zero().dot(dir) > 0.985)
                .map(|p| p.x.hypot(p.z))
                .fold(0.12f32, f32::max)
        })
        .collect();
    for r in 0..rings {
        let t = r as f32 / (rings - 1) as f32;
        for (s, &r0) in radius.iter().enumerate() {
            let a = std::f32::consts::TAU * s as f32 / segments as f32;
            // A bell: out from the hips quickly (clear of the hip and thigh
            // colliders), then nearly straight down.
            let rad = r0 + FLARE * t.sqrt();
            positions.push(Vec3::new(
                rad * a.cos(),
                WAIST_Y - LENGTH * t,
                rad * a.sin(),
            ));
        }
    }
    let mut triangles = Vec::new();
    for r in 0..rings - 1 {
        for s in 0..segments {
            let a = r * segments + s;
            let b = r * segments + (s + 1) % segments;
            let (c, d) = (a + segments, b + segments);
            // Angle grows from +X towards +Z, so (a, b, c) seen from outside turns
            // counter-clockwise when ordered a, c, b.
            triangles.push([a, c, b]);
            triangles.push([b, c, d]);
        }
    }
    let n = positions.len() as u32;
    Mesh {
        name: "skirt".into(),
        positions,
        triangles,
        source_vertex: (0..n).collect(),
        ..Mesh::default()
    }
}

/// The demo's skirt ([`skirt`] with [`RINGS`] and [`SEGMENTS`]) on `asset` and its pins:
/// the waist ring, the first [`SEGMENTS`] vertices.
pub fn demo_skirt(asset: &Asset) -> (Mesh, PinSelection) {
    (
        skirt(asset, RINGS, SEGMENTS),
        PinSelection::Vertices((0..SEGMENTS).collect()),
    )
}

/// The demo's skirt simulated on its [`CLIP`] (`rigport cloth`'s pipeline with its default
/// options: the clip's 30 fps, 1200 substeps per second) and baked in: the character with
/// the skirt as its second mesh, animated by one morph target per frame, and the clip alone.
/// `progress(done, total)` is called after every simulated frame; warnings (none expected)
/// go into `warnings`.
///
/// ```no_run
/// let demo = rigport_demo::build(1)?;
/// let (asset, report) = rigport_demo::skirt::bake(&demo, &mut Vec::new(), |_, _| {})?;
/// assert_eq!(asset.meshes[1].name, "skirt");
/// assert_eq!(report.frames, 61);
/// # Ok::<(), rigport_demo::DemoError>(())
/// ```
///
/// # Errors
/// [`DemoError::Cloth`] (a rigport bug).
pub fn bake(
    demo: &Demo,
    warnings: &mut Vec<Warning>,
    progress: impl FnMut(usize, usize),
) -> Result<(Asset, ClothReport), DemoError> {
    let mut asset = demo.asset.clone();
    let (mesh, pins) = demo_skirt(&asset);
    let opts = ClothOptions {
        clip: Some(CLIP),
        ..ClothOptions::default()
    };
    let report = asset::run(
        &mut asset,
        GarmentSource::Mesh(Box::new(mesh)),
        &[pins],
        &opts,
        None,
        warnings,
        progress,
    )
    .map_err(DemoError::Cloth)?;
    Ok((asset, report))
}
