//! `verify --picture`: the worst frame of the worst clip, the reference coloured by each
//! vertex's deviation at that frame (`rigport_render::deviation`), its worst vertices
//! beyond the tolerance ringed.

use std::path::Path;

use rigport_compare::side::{Posed, Scratch, Side};
use rigport_model::glam::Vec3;
use rigport_render::deviation::{DeviationPicture, render_deviation};

use super::findings::{Findings, compile_clip, frame_of};
use crate::PipelineError;
use crate::outputs::write_file;

/// Vertices ringed at most.
const MARKED: usize = 32;
/// The picture's panels, pixels.
const SIZE: u32 = 512;

/// A ringed vertex: reference mesh and vertex, and its pixel in the picture.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Mark {
    pub mesh: usize,
    pub vertex: usize,
    pub deviation: f64,
    pub pixel: Option<[f32; 2]>,
}

/// Draws and writes the picture; the vertices ringed.
///
/// # Errors
/// A side cannot be evaluated; the picture cannot be drawn or written.
pub(crate) fn write(f: &Findings<'_>, path: &Path) -> Result<Vec<Mark>, PipelineError> {
    let (reference, candidate) = f.assets;
    // The clip with the largest vertex deviation, at its worst frame.
    let worst = f.results.iter().max_by(|a, b| {
        a.deviation
            .vertices
            .max
            .total_cmp(&b.deviation.vertices.max)
    });
    let (clips, time, offset) = match worst {
        Some(r) => (
            r.clips,
            r.deviation.vertices.at.map_or(0.0, |a| a.time),
            r.offset.unwrap_or(0.0),
        ),
        None => ((None, None), 0.0, 0.0),
    };
    let failed = |e| PipelineError::step("the picture's frame cannot be evaluated", e);
    let rs = Side::new(reference, frame_of(reference)).map_err(failed)?;
    let mut to_cand = frame_of(candidate);
    if let Some(p) = &f.placement {
        to_cand = p.inverse() * to_cand;
    }
    let cs = Side::new(candidate, to_cand).map_err(failed)?;
    let (rc, cc) = (
        compile_clip(reference, clips.0)?,
        compile_clip(candidate, clips.1)?,
    );
    let (mut rp, mut cp) = (Posed::default(), Posed::default());
    rs.evaluate(rc.as_ref(), time, true, &mut Scratch::default(), &mut rp)
        .map_err(failed)?;
    cs.evaluate(
        cc.as_ref(),
        time + offset,
        true,
        &mut Scratch::default(),
        &mut cp,
    )
    .map_err(failed)?;
    let mut deviation: Vec<Vec<f32>> = reference.meshes.iter().map(|_| Vec::new()).collect();
    let mut ranked: Vec<(f64, usize, usize)> = Vec::new();
    for pair in &f.mesh_pairs {
        let (Some(rv), Some(cv)) = (
            rp.positions.get(pair.reference),
            cp.positions.get(pair.candidate),
        ) else {
            continue;
        };
        let dev: Vec<f32> = rv
            .iter()
            .enumerate()
            .map(|(v, p)| {
                let d = pair.distance(v, *p, cv);
                if d.is_finite() {
                    if d > f.within() {
                        ranked.push((d, pair.reference, v));
                    }
                    d as f32
                } else {
                    0.0
                }
            })
            .collect();
        deviation[pair.reference] = dev;
    }
    ranked.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)).then(a.2.cmp(&b.2)));
    ranked.truncate(MARKED);
    let marked: Vec<(usize, usize)> = ranked.iter().map(|&(_, m, v)| (m, v)).collect();
    let positions: Vec<Vec<Vec3>> = rp
        .positions
        .iter()
        .map(|p| p.iter().map(|v| v.as_vec3()).collect())
        .collect();
    let top = deviation
        .iter()
        .flatten()
        .fold(0.0f32, |a, &b| a.max(b))
        .max(f.within() as f32);
    let picture = DeviationPicture {
        meshes: &reference.meshes,
        positions: &positions,
        deviation: &deviation,
        scale_max: top,
        marked: &marked,
    };
    let cannot = |e| PipelineError::step("cannot draw the picture", e);
    let (fb, pixels) = render_deviation(&picture, SIZE, SIZE).map_err(cannot)?;
    let bytes = rigport_render::encode_png(&fb).map_err(cannot)?;
    write_file(path, &bytes)?;
    Ok(ranked
        .iter()
        .zip(pixels)
        .map(|(&(deviation, mesh, vertex), pixel)| Mark {
            mesh,
            vertex,
            deviation,
            pixel,
        })
        .collect())
}
