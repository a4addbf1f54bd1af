//! Automatic weights (bone heat) on the corpus's Pinocchio rigs, scored against
//! Pinocchio's own `attachment.out` for the same mesh and skeleton (issue 33):
//! - the mean over vertices of the L1 distance between the weight rows;
//! - over 128 seeded random poses (each bone turned up to 45° about a random axis), the
//!   mean and max distance between the vertices skinned with either set, relative to the
//!   skeleton's height.
//!
//! Measured (dev build): L1 0.043-0.068, posed mean 0.03-0.22%, max 0.5-4.6% of the
//! height, 0.1 s for `human_model1`'s 13k vertices and 17 bones.
//!
//! Skips with a message when `../shared/corpus` is absent; fails then when `CI` is set.
//! `cargo test -p rigport-deform --test weights_corpus -- --nocapture` prints the table.

use std::time::Instant;

use rigport_deform::weights::{bone_heat, Bone, HeatOptions};
use rigport_eval::{Pose, Rig, RigOutput};
use rigport_model::glam::{Quat, Vec3};
use rigport_model::{Influence, Influences};

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

/// The scores of one rig: (mean L1, mean and max posed distance over the height).
fn score(label: &str, files: [&str; 3]) -> Option<(f64, f64, f64)> {
    let paths: Vec<_> = files
        .iter()
        .map(|f| rigport_testkit::corpus(f))
        .collect::<Option<_>>()?;
    let imported =
        rigport_import::pinocchio::import(&paths[0], &paths[1], &paths[2]).expect("imports");
    let theirs = imported.asset;
    let text = std::fs::read_to_string(&paths[1]).expect("skeleton");
    let pin = rigport_import::pinocchio::parse_skeleton(&text, &paths[1]).expect("skeleton parses");
    // Heat bone k - 1 is the bone ending at Pinocchio joint k: the skin joint `bone_<k>`.
    let bones: Vec<Bone> = (1..pin.positions.len())
        .map(|k| Bone {
            head: pin.positions[pin.parents[k].expect("a parent") as usize],
            tail: pin.positions[k],
        })
        .collect();
    let joint_of: Vec<u32> = (1..pin.positions.len())
        .map(|k| {
            theirs
                .skeleton
                .find(&format!("bone_{k}"))
                .expect("bone joint")
                .0
        })
        .collect();
    let mesh = &theirs.meshes[0];
    let start = Instant::now();
    let heat = bone_heat(
        &mesh.positions,
        &mesh.triangles,
        &bones,
        &HeatOptions::default(),
    )
    .expect("weights");
    let seconds = start.elapsed().as_secs_f64();
    let mut ours = theirs.clone();
    ours.skins[0].influences = Influences::from_rows(heat.rows.iter().map(|r| {
        r.iter()
            .map(|&(b, w)| Influence {
                joint: joint_of[b as usize],
                weight: w,
            })
            .collect::<Vec<_>>()
    }));
    // L1 between rows over the palette.
    let joints = theirs.skeleton.len();
    let mut l1 = 0.0f64;
    for (a, b) in theirs.skins[0]
        .influences
        .rows()
        .zip(ours.skins[0].influences.rows())
    {
        let mut dense = vec![0.0f64; joints];
        a.iter()
            .for_each(|i| dense[i.joint as usize] += f64::from(i.weight));
        b.iter()
            .for_each(|i| dense[i.joint as usize] -= f64::from(i.weight));
        l1 += dense.iter().map(|d| d.abs()).sum::<f64>();
    }
    l1 /= mesh.positions.len() as f64;
    let ys: Vec<f32> = pin.positions.iter().map(|p| p.y).collect();
    let height = f64::from(
        ys.iter().copied().fold(f32::MIN, f32::max) - ys.iter().copied().fold(f32::MAX, f32::min),
    );
    let (rig_a, rig_b) = (
        Rig::new(&theirs).expect("rig"),
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
            t.rotation =
                Quat::from_axis_angle(axis, (rng.next() * 2.0 - 1.0) * std::f32::consts::FRAC_PI_4)
                    * t.rotation;
        }
        rig_a.evaluate(&pose, &mut out_a).expect("evaluates");
        rig_b.evaluate(&pose, &mut out_b).expect("evaluates");
        for (p, q) in out_a.positions[0].iter().zip(&out_b.positions[0]) {
            let d = f64::from(p.distance(*q)) / height;
            sum += d;
            count += 1;
            worst = worst.max(d);
        }
    }
    let mean = sum / count as f64;
    eprintln!(
        "{label}: {} vertices, {} bones, {seconds:.2} s; L1 {l1:.3}, posed mean {:.2}%, max {:.2}% of the height; repairs {:?}",
        mesh.positions.len(), bones.len(), 100.0 * mean, 100.0 * worst, heat.repairs
    );
    Some((l1, mean, worst))
}

#[test]
fn bone_heat_is_close_to_pinocchios_own_weights() {
    for (label, mesh, skeleton, attachment) in rigport_testkit::PINOCCHIO_RIGS {
        let Some((l1, mean, max)) = score(label, [mesh, skeleton, attachment]) else {
            return;
        };
        // Issue 33's absolute bounds (Blender's own scores may be larger on a rig; they are
        // the other half of the bound, measured by tools/ where bpy is installed).
        assert!(l1 <= 0.15, "{label}: L1 {l1}");
        assert!(mean <= 0.005, "{label}: posed mean {mean}");
        assert!(max <= 0.05, "{label}: posed max {max}");
    }
}
