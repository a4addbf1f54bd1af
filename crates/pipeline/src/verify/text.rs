//! `verify`'s report: text for people ([`summary`]) and JSON for machines ([`json`]).

use std::fmt::Write as _;

use rigport_compare::deviation::{At, Deviation};
use serde_json::{Value, json};

use super::findings::{ClipResult, Findings};
use super::options::Times;
use super::picture::Mark;

/// Vertices beyond the tolerance listed in the text (all of them, up to
/// [`JSON_VERTICES`], in the JSON).
const TEXT_VERTICES: usize = 12;
/// Vertices beyond the tolerance listed in the JSON.
const JSON_VERTICES: usize = 10_000;

/// A clip's name, or "(rest pose)".
fn clip_name(f: &Findings<'_>, side: usize, k: Option<usize>) -> String {
    let asset = if side == 0 { f.assets.0 } else { f.assets.1 };
    match k.and_then(|k| asset.clips.get(k)) {
        Some(c) => format!("{:?}", c.name),
        None => "(rest pose)".into(),
    }
}

/// Reference joint `j`'s name.
fn joint_name(f: &Findings<'_>, j: usize) -> String {
    f.assets
        .0
        .skeleton
        .joints()
        .get(j)
        .map_or_else(String::new, |j| j.name.clone())
}

/// Reference mesh `m`'s name (or its index when unnamed).
fn mesh_name(f: &Findings<'_>, m: usize) -> String {
    match f.assets.0.meshes.get(m) {
        Some(mesh) if !mesh.name.is_empty() => format!("{:?}", mesh.name),
        _ => format!("#{m}"),
    }
}

/// A length in metres, with its fraction of the diagonal.
fn length(f: &Findings<'_>, d: f64) -> String {
    format!("{d:.3e} m ({:.3e} of the diagonal)", d / f.diagonal)
}

/// The vertices beyond the tolerance, worst first: `(mesh pair, vertex, deviation)`.
pub(crate) fn beyond(f: &Findings<'_>, r: &ClipResult) -> Vec<(usize, usize, f64)> {
    let within = f.within();
    let mut out: Vec<(usize, usize, f64)> = Vec::new();
    for (k, per_vertex) in r.deviation.per_vertex.iter().enumerate() {
        let mesh = f.mesh_pairs[k].reference;
        out.extend(
            per_vertex
                .iter()
                .enumerate()
                .filter(|(_, d)| **d > within)
                .map(|(v, d)| (mesh, v, *d)),
        );
    }
    out.sort_by(|a, b| b.2.total_cmp(&a.2).then(a.0.cmp(&b.0)).then(a.1.cmp(&b.1)));
    out
}

/// The text report.
pub(crate) fn summary(f: &Findings<'_>) -> String {
    let mut s = String::new();
    let (r, c) = f.assets;
    for (role, label, a) in [("REFERENCE", &f.labels.0, r), ("CANDIDATE", &f.labels.1, c)] {
        let _ = writeln!(
            s,
            "{role}: {label}: {} joints, {} meshes, {} clips",
            a.skeleton.len(),
            a.meshes.len(),
            a.clips.len()
        );
    }
    let _ = writeln!(
        s,
        "frame: both seen +Y up in metres; the reference's diagonal is {:.4} m, the tolerance {:e} of it ({:.3e} m)",
        f.diagonal,
        f.tolerance,
        f.within()
    );
    let by_name = f.joints.pairs.iter().filter(|p| p.2).count();
    let _ = writeln!(
        s,
        "joints: {} paired ({by_name} by name, {} by the naming rule)",
        f.joints.pairs.len(),
        f.joints.pairs.len() - by_name
    );
    only(
        &mut s,
        "joints",
        &f.joints.only_reference,
        &f.joints.only_candidate,
        |k| r.skeleton.joints().get(k).map(|j| j.name.clone()),
        |k| c.skeleton.joints().get(k).map(|j| j.name.clone()),
    );
    for (pair, &(_, cm, named)) in f.mesh_pairs.iter().zip(&f.meshes.pairs) {
        let _ = writeln!(
            s,
            "mesh {} ~ {:?} (by {}): {} vertices, {} (worst {:.3e} m, reference vertex {})",
            mesh_name(f, pair.reference),
            c.meshes[cm].name,
            if named { "name" } else { "order" },
            pair.map.len(),
            pair.map.kind.as_str(),
            pair.map.worst.0,
            pair.map.worst.1
        );
    }
    only(
        &mut s,
        "meshes",
        &f.meshes.only_reference,
        &f.meshes.only_candidate,
        |k| r.meshes.get(k).map(|m| m.name.clone()),
        |k| c.meshes.get(k).map(|m| m.name.clone()),
    );
    for (m, ro, co) in &f.morphs_only {
        let _ = writeln!(
            s,
            "morph targets of mesh {}: only in the reference: {ro:?}; only in the candidate: {co:?}",
            mesh_name(f, *m)
        );
    }
    only(
        &mut s,
        "clips",
        &f.clips.only_reference,
        &f.clips.only_candidate,
        |k| r.clips.get(k).map(|x| x.name.clone()),
        |k| c.clips.get(k).map(|x| x.name.clone()),
    );
    if let Some(p) = &f.placement {
        let _ = writeln!(
            s,
            "CANDIDATE is the REFERENCE {}; compared with that undone:",
            p.describe(f.within()).join(" and ")
        );
    }
    for result in &f.results {
        clip_text(&mut s, f, result);
    }
    let verdict = if f.passed() {
        format!(
            "PASS: the candidate plays like the reference within {:e} of its diagonal",
            f.tolerance
        )
    } else {
        format!(
            "FAIL: the candidate differs from the reference beyond {:e} of its diagonal",
            f.tolerance
        )
    };
    let _ = writeln!(s, "{verdict}");
    s
}

/// "<what> only in the reference: ...; only in the candidate: ..." when there are any.
fn only(
    s: &mut String,
    what: &str,
    reference: &[usize],
    candidate: &[usize],
    reference_name: impl Fn(usize) -> Option<String>,
    candidate_name: impl Fn(usize) -> Option<String>,
) {
    let list = |ks: &[usize], pick: &dyn Fn(usize) -> Option<String>| {
        ks.iter()
            .filter_map(|&k| pick(k))
            .map(|n| format!("{n:?}"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    if !reference.is_empty() {
        let _ = writeln!(
            s,
            "{what} only in the reference: {}",
            list(reference, &reference_name)
        );
    }
    if !candidate.is_empty() {
        let _ = writeln!(
            s,
            "{what} only in the candidate: {}",
            list(candidate, &candidate_name)
        );
    }
}

/// Where: "frame F (T s), joint "J"" or "..., mesh M vertex V".
fn at_text(f: &Findings<'_>, at: Option<At>, joint: bool) -> String {
    let Some(at) = at else {
        return "-".into();
    };
    let what = if joint {
        format!("joint {:?}", joint_name(f, at.index))
    } else {
        format!("mesh {} vertex {}", mesh_name(f, at.mesh), at.index)
    };
    format!("{what} at frame {} ({:.4} s)", at.frame, at.time)
}

fn clip_text(s: &mut String, f: &Findings<'_>, r: &ClipResult) {
    let how = match r.times_kind {
        Times::KeyUnion => "both clips' key times".to_string(),
        Times::AtKeys => "the key times both share".to_string(),
        Times::Fps(fps) => format!("{fps} frames per second"),
    };
    let _ = writeln!(
        s,
        "clip {} ~ {} ({} times: {how}):",
        clip_name(f, 0, r.clips.0),
        clip_name(f, 1, r.clips.1),
        r.times.len()
    );
    if let Some(offset) = r.offset {
        let _ = writeln!(
            s,
            "  CANDIDATE's clip is the REFERENCE's shifted by {offset:+.4} s (a time offset: the candidate plays it {} s {})",
            format_args!("{:.4}", offset.abs()),
            if offset > 0.0 { "later" } else { "earlier" }
        );
    }
    let d = &r.deviation;
    if d.vertices.count > 0 {
        let _ = writeln!(
            s,
            "  vertices: max {}, mean {}; worst: {}",
            length(f, d.vertices.max),
            length(f, d.vertices.mean()),
            at_text(f, d.vertices.at, false)
        );
    }
    if d.joint_positions.count > 0 {
        let _ = writeln!(
            s,
            "  joint positions: max {}, mean {:.3e} m; worst: {}",
            length(f, d.joint_positions.max),
            d.joint_positions.mean(),
            at_text(f, d.joint_positions.at, true)
        );
        let _ = writeln!(
            s,
            "  joint rotations: max {:.4} deg, mean {:.4} deg; worst: {}; own rotation (relative to the parent): max {:.4} deg, {}",
            d.joint_rotations.max.to_degrees(),
            d.joint_rotations.mean().to_degrees(),
            at_text(f, d.joint_rotations.at, true),
            d.local_rotations.max.to_degrees(),
            at_text(f, d.local_rotations.at, true)
        );
    }
    let beyond = beyond(f, r);
    if !beyond.is_empty() {
        let listed: Vec<String> = beyond
            .iter()
            .take(TEXT_VERTICES)
            .map(|(m, v, _)| format!("{}:{v}", mesh_name(f, *m)))
            .collect();
        let more = beyond.len().saturating_sub(TEXT_VERTICES);
        let tail = if more > 0 {
            format!(" and {more} more")
        } else {
            String::new()
        };
        let _ = writeln!(
            s,
            "  {} vertices beyond the tolerance, worst first (mesh:vertex): {}{tail}",
            beyond.len(),
            listed.join(", ")
        );
    }
    let _ = writeln!(
        s,
        "  {}",
        if r.passed {
            "within the tolerance"
        } else {
            "beyond the tolerance"
        }
    );
}

/// A deviation as JSON; `joint` names the place by joint, else by mesh and vertex.
fn deviation_json(f: &Findings<'_>, d: &Deviation, joint: bool, angle: bool) -> Value {
    let k = if angle {
        180.0 / std::f64::consts::PI
    } else {
        1.0
    };
    let at = d.at.map(|at| {
        if joint {
            json!({"frame": at.frame, "time": at.time, "joint": joint_name(f, at.index), "joint_index": at.index})
        } else {
            json!({"frame": at.frame, "time": at.time, "mesh": at.mesh, "vertex": at.index})
        }
    });
    let mut v = json!({"max": d.max * k, "mean": d.mean() * k, "worst": at});
    if !angle {
        v["max_relative"] = json!(d.max / f.diagonal);
        v["mean_relative"] = json!(d.mean() / f.diagonal);
    }
    v
}

/// The JSON report.
pub(crate) fn json(f: &Findings<'_>, marks: &[Mark]) -> String {
    let (r, c) = f.assets;
    let names =
        |ks: &[usize], n: &dyn Fn(usize) -> String| ks.iter().map(|&k| n(k)).collect::<Vec<_>>();
    let side = |label: &str, a: &rigport_model::Asset| {
        json!({
            "file": label,
            "joints": a.skeleton.len(),
            "meshes": a.meshes.iter().map(|m| m.name.clone()).collect::<Vec<_>>(),
            "clips": a.clips.iter().map(|c| c.name.clone()).collect::<Vec<_>>(),
        })
    };
    let clips: Vec<Value> = f
        .results
        .iter()
        .map(|res| {
            let beyond = beyond(f, res);
            json!({
                "reference": res.clips.0.and_then(|k| r.clips.get(k)).map(|c| c.name.clone()),
                "candidate": res.clips.1.and_then(|k| c.clips.get(k)).map(|c| c.name.clone()),
                "times": res.times.len(),
                "time_offset": res.offset,
                "passed": res.passed,
                "vertices": deviation_json(f, &res.deviation.vertices, false, false),
                "joint_positions": deviation_json(f, &res.deviation.joint_positions, true, false),
                "joint_rotations_deg": deviation_json(f, &res.deviation.joint_rotations, true, true),
                "own_rotations_deg": deviation_json(f, &res.deviation.local_rotations, true, true),
                "vertices_beyond_count": beyond.len(),
                "vertices_beyond": beyond.iter().take(JSON_VERTICES).map(|(m, v, d)| json!({"mesh": m, "vertex": v, "deviation": d})).collect::<Vec<_>>(),
            })
        })
        .collect();
    let meshes: Vec<Value> = f
        .mesh_pairs
        .iter()
        .zip(&f.meshes.pairs)
        .map(|(p, &(_, cm, named))| {
            json!({
                "reference": p.reference, "candidate": cm, "by": if named { "name" } else { "order" },
                "vertices": p.map.len(), "map": p.map.kind.as_str(),
                "map_worst_distance": p.map.worst.0, "map_worst_vertex": p.map.worst.1,
            })
        })
        .collect();
    let placement = f.placement.map(|p| {
        json!({
            "scale": p.scale,
            "rotation_xyzw": p.rotation.to_array(),
            "translation": p.translation.to_array(),
            "description": p.describe(f.within()),
        })
    });
    let report = json!({
        "reference": side(&f.labels.0, r),
        "candidate": side(&f.labels.1, c),
        "diagonal": f.diagonal,
        "tolerance": f.tolerance,
        "passed": f.passed(),
        "placement": placement,
        "joints": {
            "paired": f.joints.pairs.len(),
            "by_name": f.joints.pairs.iter().filter(|p| p.2).count(),
            "only_reference": names(&f.joints.only_reference, &|k| r.skeleton.joints()[k].name.clone()),
            "only_candidate": names(&f.joints.only_candidate, &|k| c.skeleton.joints()[k].name.clone()),
        },
        "meshes": meshes,
        "meshes_only_reference": names(&f.meshes.only_reference, &|k| r.meshes[k].name.clone()),
        "meshes_only_candidate": names(&f.meshes.only_candidate, &|k| c.meshes[k].name.clone()),
        "morph_targets_only": f.morphs_only.iter().map(|(m, a, b)| json!({"mesh": m, "only_reference": a, "only_candidate": b})).collect::<Vec<_>>(),
        "clips_only_reference": names(&f.clips.only_reference, &|k| r.clips[k].name.clone()),
        "clips_only_candidate": names(&f.clips.only_candidate, &|k| c.clips[k].name.clone()),
        "clips": clips,
        "picture_marks": marks.iter().map(|m| json!({"mesh": m.mesh, "vertex": m.vertex, "deviation": m.deviation, "pixel": m.pixel})).collect::<Vec<_>>(),
    });
    let mut text = serde_json::to_string_pretty(&report).unwrap_or_default();
    text.push('\n');
    text
}
