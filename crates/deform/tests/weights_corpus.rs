//! Automatic weights (bone heat) on the corpus's Pinocchio rigs, rigport's and Blender's,
//! both scored against Pinocchio's own `attachment.out` for the same mesh and skeleton, the
//! same way, in the same run (issue 33):
//! - the mean over vertices of the L1 distance between the weight rows;
//! - over 128 seeded random poses (each bone turned up to 45° about a random axis), the
//!   mean and max distance between the vertices skinned with either set, relative to the
//!   skeleton's height.
//!
//! Blender's weights come from `tools/blender/auto_weights.py` (armature parent with
//! automatic weights on the same vertices and bones; one Blender session for all rigs,
//! about 3 s). On each rig, each of rigport's three scores must be at most the larger of
//! the absolute bound (L1 0.15, mean 0.5%, max 5%) and Blender's score.
//!
//! Measured (dev build; BENCHMARKS.md has the table): rigport L1 0.006-0.068, posed mean
//! 0.03-0.22%, max 0.5-4.6% of the height, below Blender's on every rig and score (Blender
//! L1 0.035-0.278, mean 0.14-0.72%, max 1.3-6.0%); 11 s in all, 5 s without Blender.
//!
//! A second test shrinks `human_model1` by 1e-4, where Blender's solver gives up and rigport
//! must give the full size's weights.
//!
//! Skips with a message when `../shared/corpus` is absent, and holds rigport to the absolute
//! bounds alone when Blender's `bpy` is absent; either fails when `CI` is set.
//! `cargo test -p rigport-deform --test weights_corpus -- --nocapture` prints the table.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use rigport_deform::weights::{bone_heat, Bone, HeatOptions};
use rigport_eval::{Pose, Rig, RigOutput};
use rigport_model::glam::{Quat, Vec3};
use rigport_model::{Asset, Influence, Influences};

/// The absolute bounds: mean L1, posed mean and max over the height.
const BOUNDS: Scores = Scores {
    l1: 0.15,
    mean: 0.005,
    max: 0.05,
};

/// A small seeded generator (SplitMix64), in [0, 1).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f32 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
    }
}

/// How far a set of weights is from Pinocchio's: mean L1 between rows, and the mean and
/// max posed vertex distance over the skeleton's height.
#[derive(Clone, Copy, Debug)]
struct Scores {
    l1: f64,
    mean: f64,
    max: f64,
}

impl Scores {
    /// The scores of `self` above `max(BOUNDS, peer)`, named.
    fn over(&self, peer: Option<Scores>) -> Vec<String> {
        let bound = |b: f64, p: Option<f64>| p.map_or(b, |p| b.max(p));
        [
            ("L1", self.l1, bound(BOUNDS.l1, peer.map(|p| p.l1))),
            ("mean", self.mean, bound(BOUNDS.mean, peer.map(|p| p.mean))),
            ("max", self.max, bound(BOUNDS.max, peer.map(|p| p.max))),
        ]
        .iter()
        .filter(|(_, v, b)| v > b)
        .map(|(what, v, b)| format!("{what} {v:.4} > {b:.4}"))
        .collect()
    }
}

/// One corpus rig with Pinocchio's weights, and what scoring another set needs.
struct Reference {
    files: [PathBuf; 3],
    /// The rig with Pinocchio's own weights.
    pinocchio: Asset,
    /// Heat bone `k - 1` is the bone ending at Pinocchio joint `k`.
    bones: Vec<Bone>,
    /// The skin joint `bone_<k>` of each heat bone.
    joint_of: Vec<u32>,
    /// The skin joint `root` (a vertex without weights stays with it, at rest).
    root: u32,
    /// The skeleton's height (y extent of its joints).
    height: f64,
}

impl Reference {
    fn load(files: [&str; 3]) -> Option<Self> {
        let paths: Vec<PathBuf> = files
            .iter()
            .map(|f| rigport_testkit::corpus(f))
            .collect::<Option<_>>()?;
        let files: [PathBuf; 3] = paths.try_into().expect("three files");
        let pinocchio = rigport_import::pinocchio::import(&files[0], &files[1], &files[2])
            .expect("imports")
            .asset;
        let text = std::fs::read_to_string(&files[1]).expect("skeleton");
        let pin = rigport_import::pinocchio::parse_skeleton(&text, &files[1]).expect("parses");
        let bones = (1..pin.positions.len())
            .map(|k| Bone {
                head: pin.positions[pin.parents[k].expect("a parent")],
                tail: pin.positions[k],
            })
            .collect();
        let joint = |name: &str| pinocchio.skeleton.find(name).expect("skin joint").0;
        let joint_of = (1..pin.positions.len())
            .map(|k| joint(&format!("bone_{k}")))
            .collect();
        let ys = pin.positions.iter().map(|p| p.y);
        let height = f64::from(ys.clone().fold(f32::MIN, f32::max) - ys.fold(f32::MAX, f32::min));
        let root = joint("root");
        Some(Self {
            files,
            pinocchio,
            bones,
            joint_of,
            root,
            height,
        })
    }

    /// Scores `rows` (per mesh vertex, `(heat bone, weight)` pairs; each row is normalized
    /// here, as Blender's Armature modifier divides by the row's sum; an empty row stays at
    /// rest, as a vertex without weights does in Blender).
    fn score(&self, rows: &[Vec<(u32, f32)>]) -> Scores {
        let theirs = &self.pinocchio;
        assert_eq!(
            rows.len(),
            theirs.meshes[0].positions.len(),
            "one row per vertex"
        );
        let joints = theirs.skeleton.len();
        let normalized = rows.iter().map(|r| {
            let sum: f32 = r.iter().map(|&(_, w)| w).sum();
            r.iter().map(move |&(b, w)| Influence {
                joint: self.joint_of[b as usize],
                weight: w / sum,
            })
        });
        let mut ours = theirs.clone();
        ours.skins[0].influences = Influences::from_rows(normalized.clone());
        // L1 between rows over the palette (an empty row is 1 from any row).
        let mut l1 = 0.0f64;
        let mut dense = vec![0.0f64; joints];
        for (a, b) in theirs.skins[0].influences.rows().zip(normalized) {
            dense.iter_mut().for_each(|d| *d = 0.0);
            a.iter()
                .for_each(|i| dense[i.joint as usize] += f64::from(i.weight));
            b.for_each(|i| dense[i.joint as usize] -= f64::from(i.weight));
            l1 += dense.iter().map(|d| d.abs()).sum::<f64>();
        }
        l1 /= rows.len() as f64;
        // Posed: an empty row is bound to the root, which no pose turns.
        let at_rest = [Influence {
            joint: self.root,
            weight: 1.0,
        }];
        let posed = Influences::from_rows(ours.skins[0].influences.rows().map(|r| {
            if r.is_empty() {
                at_rest.to_vec()
            } else {
                r.to_vec()
            }
        }));
        ours.skins[0].influences = posed;
        let (rig_a, rig_b) = (
            Rig::new(theirs).expect("rig"),
            Rig::new(&ours).expect("rig"),
        );
        let (mut out_a, mut out_b) = (RigOutput::default(), RigOutput::default());
        let mut rng = Rng(17);
        let (mut sum, mut count, mut worst) = (0.0f64, 0usize, 0.0f64);
        for _ in 0..128 {
            let mut pose = Pose::rest(&theirs.skeleton);
            for t in pose.local.iter_mut().skip(1) {
                let axis = Vec3::new(rng.next() - 0.5, rng.next() - 0.5, rng.next() - 0.5)
                    .normalize_or(Vec3::X);
                let angle = (rng.next() * 2.0 - 1.0) * std::f32::consts::FRAC_PI_4;
                t.rotation = Quat::from_axis_angle(axis, angle) * t.rotation;
            }
            rig_a.evaluate(&pose, &mut out_a).expect("evaluates");
            rig_b.evaluate(&pose, &mut out_b).expect("evaluates");
            for (p, q) in out_a.positions[0].iter().zip(&out_b.positions[0]) {
                let d = f64::from(p.distance(*q)) / self.height;
                sum += d;
                count += 1;
                worst = worst.max(d);
            }
        }
        Scores {
            l1,
            mean: sum / count as f64,
            max: worst,
        }
    }

    /// rigport's bone heat: rows per mesh vertex, its wall time, what it repaired.
    fn rigport(&self) -> (Vec<Vec<(u32, f32)>>, f64, String) {
        let mesh = &self.pinocchio.meshes[0];
        let start = Instant::now();
        let heat = bone_heat(
            &mesh.positions,
            &mesh.triangles,
            &self.bones,
            &HeatOptions::default(),
            &|_, _| {},
        )
        .expect("weights");
        let seconds = start.elapsed().as_secs_f64();
        let r = heat.repairs;
        let repairs: Vec<String> = [
            (r.welded, "welded"),
            (r.degenerate_faces, "degenerate faces"),
            (r.non_manifold_edges, "non-manifold edges"),
            (r.unseen, "unseen"),
            (r.by_distance, "by distance"),
            (r.negative_edges, "negative edges"),
        ]
        .iter()
        .filter(|(n, _)| *n > 0)
        .map(|(n, what)| format!("{what} {n}"))
        .collect();
        (heat.rows, seconds, repairs.join(", "))
    }

    /// Blender's weights from `tools/blender/auto_weights.py`'s `out` (a row per OBJ `v`):
    /// rows per mesh vertex, the wall time of its weighting, its warnings.
    fn blender(&self, out: &Path) -> (Vec<Vec<(u32, f32)>>, f64, String) {
        let text = std::fs::read_to_string(out).expect("Blender's weights");
        let (mut seconds, mut notes, mut by_source) = (f64::NAN, Vec::new(), Vec::new());
        for line in text.lines() {
            if let Some(s) = line.strip_prefix("# seconds ") {
                seconds = s.parse().expect("seconds");
            } else if let Some(note) = line.strip_prefix("# ") {
                notes.push(note.to_owned());
            } else {
                let row: Vec<(u32, f32)> = line
                    .split_ascii_whitespace()
                    .enumerate()
                    .map(|(b, w)| (b as u32, w.parse::<f32>().expect("weight")))
                    .filter(|&(_, w)| w > 0.0)
                    .collect();
                by_source.push(row);
            }
        }
        let mesh = &self.pinocchio.meshes[0];
        assert_eq!(
            by_source.len(),
            mesh.source_vertex_count(),
            "a row per OBJ v"
        );
        let rows = (0..mesh.positions.len())
            .map(|v| by_source[mesh.source_vertex.get(v).map_or(v, |&s| s as usize)].clone())
            .collect();
        (rows, seconds, notes.join("; "))
    }
}

/// Runs `tools/blender/auto_weights.py` once on every `(label, mesh, skeleton)`: each one's
/// output file.
fn run_blender(python: &Path, inputs: &[(&str, &Path, &Path)], dir: &Path) -> Vec<PathBuf> {
    let outs: Vec<PathBuf> = inputs
        .iter()
        .map(|(label, _, _)| dir.join(format!("{label}.txt")))
        .collect();
    let mut command = Command::new(python);
    command.arg(rigport_testkit::repo().join("tools/blender/auto_weights.py"));
    for ((_, mesh, skeleton), out) in inputs.iter().zip(&outs) {
        command.arg(mesh).arg(skeleton).arg(out);
    }
    let output = command.output().expect("Blender's python runs");
    assert!(
        output.status.success(),
        "auto_weights.py: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    outs
}

/// `text` (an OBJ when `obj`, else a `skeleton.out`) with the coordinates of its `v` lines
/// (OBJ) or joint lines (fields 2-4 of 5) multiplied by `scale`.
fn scaled(text: &str, scale: f32, obj: bool) -> String {
    let mut out = String::with_capacity(text.len());
    for line in text.lines() {
        let fields: Vec<&str> = line.split_ascii_whitespace().collect();
        let position = if obj {
            fields.first() == Some(&"v")
        } else {
            fields.len() == 5
        };
        let coordinates = if position { 1..4 } else { 0..0 };
        let fields: Vec<String> = fields
            .iter()
            .enumerate()
            .map(|(i, f)| {
                if coordinates.contains(&i) {
                    (f.parse::<f32>().expect("a coordinate") * scale).to_string()
                } else {
                    (*f).to_owned()
                }
            })
            .collect();
        out.push_str(&fields.join(" "));
        out.push('\n');
    }
    out
}

/// human_model1 shrunk by 1e-4: Blender 4.5's bone heat gives up on it ("Bone Heat
/// Weighting: failed to find solution for one or more bones", every vertex left without
/// weights), rigport's weights it as the mesh at its own size (the method is scale-free:
/// the cotangent weights do not change, and the heat `c / d²` and the vertex areas scale
/// inversely). Blender's turn checks that `auto_weights.py` records the warning whenever
/// Blender leaves a vertex without weights.
#[test]
fn bone_heat_weights_a_tiny_mesh_as_its_full_size() {
    let (label, mesh, skeleton, attachment) = rigport_testkit::PINOCCHIO_RIGS[3];
    assert_eq!(label, "model1");
    let Some(reference) = Reference::load([mesh, skeleton, attachment]) else {
        return;
    };
    let dir = tempfile::tempdir().expect("temp dir");
    let scale = 1e-4f32;
    let tiny = [dir.path().join("tiny.obj"), dir.path().join("tiny.out")];
    for (k, (from, to)) in reference.files.iter().zip(&tiny).enumerate() {
        let text = std::fs::read_to_string(from).expect("reads");
        std::fs::write(to, scaled(&text, scale, k == 0)).expect("writes");
    }
    let (full, _, _) = reference.rigport();
    let mesh = &reference.pinocchio.meshes[0];
    let positions: Vec<Vec3> = mesh.positions.iter().map(|p| *p * scale).collect();
    let bones: Vec<Bone> = reference
        .bones
        .iter()
        .map(|b| Bone {
            head: b.head * scale,
            tail: b.tail * scale,
        })
        .collect();
    let heat = bone_heat(
        &positions,
        &mesh.triangles,
        &bones,
        &HeatOptions::default(),
        &|_, _| {},
    )
    .expect("weights");
    let joints = bones.len();
    let dense = |row: &[(u32, f32)]| {
        let mut d = vec![0.0f32; joints];
        row.iter().for_each(|&(b, w)| d[b as usize] = w);
        d
    };
    let worst = full
        .iter()
        .zip(&heat.rows)
        .flat_map(|(a, b)| {
            let (a, b) = (dense(a), dense(b));
            (0..joints).map(move |j| (a[j] - b[j]).abs())
        })
        .fold(0.0f32, f32::max);
    eprintln!("rigport at 1e-4 against full size: largest weight difference {worst:.2e}");
    // f32 positions at 1e-4 of the size keep ~7 digits; 1e-3 is the prune threshold.
    assert!(worst < 1e-3, "largest weight difference {worst}");
    let Some(python) = rigport_testkit::blender_python() else {
        return;
    };
    let outs = run_blender(&python, &[("tiny", &tiny[0], &tiny[1])], dir.path());
    let (rows, _, notes) = reference.blender(&outs[0]);
    let unweighted = rows.iter().filter(|r| r.is_empty()).count();
    eprintln!(
        "Blender at 1e-4: {unweighted} of {} vertices without weights; {notes}",
        rows.len()
    );
    assert!(
        unweighted == 0 || notes.contains("failed to find solution"),
        "Blender left {unweighted} vertices without weights, and auto_weights.py recorded: {notes:?}"
    );
}

#[test]
fn bone_heat_is_as_close_to_pinocchio_as_blender_or_the_bounds() {
    let mut rigs = Vec::new();
    for (label, mesh, skeleton, attachment) in rigport_testkit::PINOCCHIO_RIGS {
        let Some(reference) = Reference::load([mesh, skeleton, attachment]) else {
            return;
        };
        rigs.push((label, reference));
    }
    let dir = tempfile::tempdir().expect("temp dir");
    let inputs: Vec<(&str, &Path, &Path)> = rigs
        .iter()
        .map(|(label, r)| (*label, r.files[0].as_path(), r.files[1].as_path()))
        .collect();
    let blender = rigport_testkit::blender_python().map(|py| run_blender(&py, &inputs, dir.path()));
    if blender.is_none() {
        eprintln!("without Blender, rigport is held to the absolute bounds alone");
    }
    eprintln!("rig        who      vertices bones  L1     mean %  max %   seconds  notes");
    let mut failures = Vec::new();
    for (i, (label, reference)) in rigs.iter().enumerate() {
        let mesh = &reference.pinocchio.meshes[0];
        let (rows, seconds, repairs) = reference.rigport();
        let ours = reference.score(&rows);
        let peer = blender.as_ref().map(|outs| {
            let (rows, seconds, notes) = reference.blender(&outs[i]);
            (reference.score(&rows), seconds, notes)
        });
        let line = |who: &str, s: &Scores, seconds: f64, notes: &str| {
            eprintln!(
                "{label:<10} {who:<8} {:>8} {:>5}  {:.3}  {:>6.3}  {:>6.2}  {seconds:>7.3}  {notes}",
                mesh.positions.len(),
                reference.bones.len(),
                s.l1,
                100.0 * s.mean,
                100.0 * s.max,
            );
        };
        line("rigport", &ours, seconds, &repairs);
        if let Some((theirs, seconds, notes)) = &peer {
            line("blender", theirs, *seconds, notes);
        }
        let over = ours.over(peer.map(|(s, _, _)| s));
        if !over.is_empty() {
            failures.push(format!("{label}: {}", over.join(", ")));
        }
    }
    assert!(
        failures.is_empty(),
        "rigport is further from Pinocchio than both the bounds and Blender: {failures:?}"
    );
}
