//! `rigport inspect`: what is in a rig.

use std::io::Write;

use anyhow::Result;
use rigport_model::{Asset, TrackTarget};
use serde::Serialize;

use crate::cli::InspectArgs;
use crate::context::Context;
use crate::input;

#[derive(Serialize)]
struct Report {
    source: String,
    name: String,
    meters_per_unit: Option<f64>,
    joints: Vec<JointReport>,
    meshes: Vec<MeshReport>,
    clips: Vec<ClipReport>,
    /// Names of the joints the rig marks as IK handles.
    ik_handles: Vec<String>,
    warnings: Vec<String>,
}

#[derive(Serialize)]
struct JointReport {
    index: usize,
    name: String,
    parent: Option<String>,
    rest_translation: [f32; 3],
    rest_rotation_xyzw: [f32; 4],
}

#[derive(Serialize)]
struct MeshReport {
    name: String,
    vertices: usize,
    source_vertices: usize,
    triangles: usize,
    has_normals: bool,
    has_uvs: bool,
    morph_targets: usize,
    bounds_min: Option<[f32; 3]>,
    bounds_max: Option<[f32; 3]>,
    attached_to: Option<String>,
    /// Present when skinned.
    skin: Option<SkinReport>,
}

#[derive(Serialize)]
struct SkinReport {
    palette_joints: usize,
    max_influences: usize,
    /// `influence_histogram[k]` = vertices with exactly k influences.
    influence_histogram: Vec<usize>,
}

#[derive(Serialize)]
struct ClipReport {
    name: String,
    duration_s: f32,
    tracks: usize,
    keys: usize,
    animated_joints: usize,
}

fn report(source: String, asset: &Asset, warnings: Vec<String>) -> Report {
    let skel = &asset.skeleton;
    let joints = skel
        .joints()
        .iter()
        .enumerate()
        .map(|(index, j)| JointReport {
            index,
            name: j.name.clone(),
            parent: j.parent.map(|p| skel.joint(p).name.clone()),
            rest_translation: j.rest_local.translation.to_array(),
            rest_rotation_xyzw: j.rest_local.rotation.to_array(),
        })
        .collect();
    let meshes = asset
        .meshes
        .iter()
        .enumerate()
        .map(|(mi, m)| {
            let skin = asset.skins.iter().find(|s| s.mesh.get() == mi).map(|s| {
                let max = s.influences.max_per_vertex();
                let mut hist = vec![0; max + 1];
                for row in s.influences.rows() {
                    hist[row.len()] += 1;
                }
                SkinReport {
                    palette_joints: s.joints.len(),
                    max_influences: max,
                    influence_histogram: hist,
                }
            });
            let bounds = m.bounds();
            MeshReport {
                name: m.name.clone(),
                vertices: m.vertex_count(),
                source_vertices: m.source_vertex_count(),
                triangles: m.triangles.len(),
                has_normals: m.normals.is_some(),
                has_uvs: m.uvs.is_some(),
                morph_targets: m.morph_targets.len(),
                bounds_min: bounds.map(|b| b.0.to_array()),
                bounds_max: bounds.map(|b| b.1.to_array()),
                attached_to: m.attached_to.map(|j| skel.joint(j).name.clone()),
                skin,
            }
        })
        .collect();
    let clips = asset
        .clips
        .iter()
        .map(|c| {
            let mut joints: Vec<usize> = c
                .tracks
                .iter()
                .filter_map(|t| match t.target {
                    TrackTarget::Translation(j)
                    | TrackTarget::Rotation(j)
                    | TrackTarget::Scale(j) => Some(j.get()),
                    TrackTarget::MorphWeights(_) => None,
                })
                .collect();
            joints.sort_unstable();
            joints.dedup();
            ClipReport {
                name: c.name.clone(),
                duration_s: c.duration(),
                tracks: c.tracks.len(),
                keys: c.tracks.iter().map(|t| t.times.len()).sum(),
                animated_joints: joints.len(),
            }
        })
        .collect();
    Report {
        source,
        name: asset.name.clone(),
        meters_per_unit: asset.meters_per_unit,
        joints,
        meshes,
        clips,
        ik_handles: asset
            .ik_handles
            .iter()
            .map(|j| skel.joint(*j).name.clone())
            .collect(),
        warnings,
    }
}

fn print_text(out: &mut impl Write, r: &Report) -> std::io::Result<()> {
    writeln!(out, "{} ({})", r.name, r.source)?;
    if let Some(m) = r.meters_per_unit {
        writeln!(out, "  units: {m} m per unit")?;
    }
    writeln!(out, "  joints: {}", r.joints.len())?;
    for j in &r.joints {
        match &j.parent {
            Some(p) => writeln!(out, "    {:4} {} <- {}", j.index, j.name, p)?,
            None => writeln!(out, "    {:4} {} (root)", j.index, j.name)?,
        }
    }
    writeln!(out, "  meshes: {}", r.meshes.len())?;
    for m in &r.meshes {
        write!(
            out,
            "    {:?}: {} vertices ({} source), {} triangles",
            m.name, m.vertices, m.source_vertices, m.triangles
        )?;
        if m.has_normals {
            write!(out, ", normals")?;
        }
        if m.has_uvs {
            write!(out, ", uvs")?;
        }
        if m.morph_targets > 0 {
            write!(out, ", {} morph targets", m.morph_targets)?;
        }
        if let Some(j) = &m.attached_to {
            write!(out, ", attached to {j}")?;
        }
        writeln!(out)?;
        if let (Some(lo), Some(hi)) = (m.bounds_min, m.bounds_max) {
            writeln!(out, "      bounds: {lo:?} .. {hi:?}")?;
        }
        if let Some(s) = &m.skin {
            writeln!(
                out,
                "      skinned by {} joints, up to {} influences per vertex",
                s.palette_joints, s.max_influences
            )?;
            let hist: Vec<String> = s
                .influence_histogram
                .iter()
                .enumerate()
                .filter(|(_, n)| **n > 0)
                .map(|(k, n)| format!("{k}: {n}"))
                .collect();
            writeln!(
                out,
                "      vertices by influence count: {}",
                hist.join(", ")
            )?;
        }
    }
    if !r.ik_handles.is_empty() {
        writeln!(out, "  IK handles: {}", r.ik_handles.join(", "))?;
    }
    writeln!(out, "  clips: {}", r.clips.len())?;
    for c in &r.clips {
        writeln!(
            out,
            "    {:?}: {:.3} s, {} tracks on {} joints, {} keys",
            c.name, c.duration_s, c.tracks, c.animated_joints, c.keys
        )?;
    }
    Ok(())
}

/// Runs `inspect`.
pub fn run(ctx: &Context, args: &InspectArgs) -> Result<()> {
    let mut reports = Vec::new();
    for plan in input::plans(&args.input)? {
        let imported = ctx.step(&format!("reading {}", plan.label()), || plan.import())?;
        // Warnings are part of the report; they do not go to stderr twice.
        let warnings = imported.warnings.iter().map(ToString::to_string).collect();
        if ctx.deny_warnings {
            ctx.report(&imported.warnings)?;
        }
        reports.push(report(plan.label(), &imported.asset, warnings));
    }
    let stdout = std::io::stdout();
    let mut out = std::io::BufWriter::new(stdout.lock());
    if args.json {
        serde_json::to_writer_pretty(&mut out, &reports)?;
        writeln!(out)?;
    } else {
        for r in &reports {
            print_text(&mut out, r)?;
            for w in &r.warnings {
                writeln!(out, "  warning: {w}")?;
            }
        }
    }
    out.flush()?;
    Ok(())
}
