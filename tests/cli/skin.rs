//! `rigport skin MESH SKELETON -o OUT` (issue 33): automatic weights written as Pinocchio's
//! `attachment.out` or as a whole rig, for a Pinocchio skeleton or any rig placed in the
//! mesh's space (`--skeleton-offset`, `--skeleton-scale`); and a CSCI 520 folder without
//! weights with `--weights auto`.

use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::Path;

use rigport_model::glam;

use crate::common::*;
use crate::gltf_read;

const MODEL1: &str = "1_pinocchio/berkeley_cs184__severus-snape_mobius-ants/human_model1";
const WALK_BVH: &str = "4_bvh/cmu_cgspeed__nobuyuki83_delfem2/walk.bvh";

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn a_pinocchio_attachment_out_reads_back_as_the_rig_skin_writes() {
    let Some(dir) = corpus(MODEL1) else {
        return;
    };
    let (mesh, skeleton) = (dir.join("Model1.obj"), dir.join("skeleton.out"));
    let out = scratch();
    let attachment = out.path().join("attachment.out");
    rigport_ok(&["skin", s(&mesh), s(&skeleton), "-o", s(&attachment), "-q"]);
    let text = std::fs::read_to_string(&attachment).unwrap();
    let obj_vertices = std::fs::read_to_string(&mesh)
        .unwrap()
        .lines()
        .filter(|l| l.starts_with("v "))
        .count();
    let rows: Vec<Vec<f32>> = (text.lines())
        .map(|l| l.split(' ').map(|w| w.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), obj_vertices);
    let joints = std::fs::read_to_string(&skeleton).unwrap().lines().count();
    for (v, row) in rows.iter().enumerate() {
        assert_eq!(row.len(), joints - 1, "row {v}: one weight per bone");
        let sum: f32 = row.iter().sum();
        assert!((sum - 1.0).abs() < 1e-4, "row {v} sums to {sum}");
    }
    // The file, read back as Pinocchio's own, is the rig `skin` writes directly.
    let (from_file, direct) = (out.path().join("file.glb"), out.path().join("direct.glb"));
    rigport_ok(&[
        "convert",
        s(&mesh),
        s(&skeleton),
        s(&attachment),
        "-o",
        s(&from_file),
        "-q",
    ]);
    rigport_ok(&["skin", s(&mesh), s(&skeleton), "-o", s(&direct), "-q"]);
    assert_valid(&direct);
    let r = rigport(&["verify", s(&direct), s(&from_file), "--tol", "1e-6"]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stdout));
    // A Pinocchio skeleton is in its mesh's space: a placement is a usage error.
    let r = rigport(&[
        "skin",
        s(&mesh),
        s(&skeleton),
        "--skeleton-scale",
        "2",
        "-o",
        s(&direct),
    ]);
    assert_eq!(
        r.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&r.stderr)
    );
}

/// An OBJ of one hexagonal tube around each bone of `bones` (head, tail), in mesh space:
/// rings at 20%..80% of the bone, so tubes do not touch at the joints.
fn tubes(bones: &[([f32; 3], [f32; 3])]) -> String {
    let mut obj = String::new();
    let mut base = 1;
    for &(a, b) in bones {
        let (a, b) = (glam::Vec3::from(a), glam::Vec3::from(b));
        let axis = (b - a).normalize();
        let side = axis.any_orthonormal_vector();
        let up = axis.cross(side);
        let radius = 0.1 * a.distance(b);
        for ring in 0..4 {
            let centre = a.lerp(b, 0.2 + 0.2 * ring as f32);
            for k in 0..6 {
                let t = k as f32 * std::f32::consts::TAU / 6.0;
                let p = centre + radius * (side * t.cos() + up * t.sin());
                writeln!(obj, "v {} {} {}", p.x, p.y, p.z).unwrap();
            }
        }
        for ring in 0..3 {
            for k in 0..6 {
                let v = |r: usize, k: usize| base + r * 6 + k % 6;
                let (a0, a1) = (v(ring, k), v(ring, k + 1));
                let (b0, b1) = (v(ring + 1, k), v(ring + 1, k + 1));
                writeln!(obj, "f {a0} {a1} {b1}\nf {a0} {b1} {b0}").unwrap();
            }
        }
        base += 24;
    }
    obj
}

#[test]
fn a_mocap_skeleton_placed_in_a_mesh_weights_each_tube_to_its_bone() {
    let Some(walk) = corpus(WALK_BVH) else {
        return;
    };
    let asset = rigport_import::bvh::import(&walk).unwrap().asset;
    let rest = asset.skeleton.model_rest_matrices();
    let (scale, offset) = (0.01_f32, glam::Vec3::new(1.0, 0.0, 2.0));
    let place = |j: usize| (rest[j].w_axis.truncate() * scale + offset).to_array();
    // The bones long enough to hold a tube, with the joint each should follow.
    let mut bones = Vec::new();
    let mut heads = Vec::new();
    let height = (0..rest.len())
        .map(|j| rest[j].w_axis.y)
        .fold(0.0, f32::max);
    for (c, parent) in asset.skeleton.parents().enumerate() {
        let Some(p) = parent else { continue };
        if rest[p.get()].w_axis.distance(rest[c].w_axis) > 0.05 * height {
            bones.push((place(p.get()), place(c)));
            heads.push(asset.skeleton.joint(p).name.clone());
        }
    }
    assert!(bones.len() > 10, "{} bones", bones.len());
    let dir = scratch();
    let mesh = dir.path().join("tubes.obj");
    std::fs::write(&mesh, tubes(&bones)).unwrap();
    let out = dir.path().join("tubes.glb");
    let placement = ["--skeleton-scale", "0.01", "--skeleton-offset", "1,0,2"];
    let mut args = vec!["skin", s(&mesh), s(&walk), "-o", s(&out), "-q"];
    args.extend(placement);
    rigport_ok(&args);
    assert_valid(&out);
    let scene = gltf_read::read(&out);
    assert!(!scene.animations.is_empty(), "the walk's clip is kept");
    let skin = &scene.skins[0];
    let mut right: HashMap<bool, usize> = HashMap::new();
    for (v, row) in skin.influences.iter().enumerate() {
        let (heaviest, _) =
            (row.iter().copied()).fold((0, -1.0), |a, b| if b.1 > a.1 { b } else { a });
        let name = &scene.node_names[heaviest];
        *right.entry(*name == heads[v / 24]).or_default() += 1;
    }
    let (ok, wrong) = (
        right.get(&true).copied().unwrap_or(0),
        right.get(&false).copied().unwrap_or(0),
    );
    eprintln!(
        "{ok} of {} tube vertices follow their bone's joint most",
        ok + wrong
    );
    assert!(
        ok as f32 >= 0.9 * (ok + wrong) as f32,
        "{ok} right, {wrong} wrong"
    );
    // At rest the mesh is where the OBJ put it, carried into the skeleton's space.
    let obj = std::fs::read_to_string(&mesh).unwrap();
    let v0: Vec<f32> = obj.lines().next().unwrap()[2..]
        .split(' ')
        .map(|t| t.parse().unwrap())
        .collect();
    let first = glam::Vec3::new(v0[0], v0[1], v0[2]);
    let expected = (first - offset) / scale;
    assert!(
        skin.positions[0].distance(expected) < 1e-3 * height,
        "{:?} vs {expected:?}",
        skin.positions[0]
    );
    // An attachment.out holds a Pinocchio skeleton's bones only.
    let att = dir.path().join("a.out");
    let r = rigport(&["skin", s(&mesh), s(&walk), "-o", s(&att)]);
    assert_eq!(
        r.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&r.stderr)
    );
    assert!(!att.exists());
}

#[test]
fn a_csci520_folder_without_weights_gets_them_with_the_flag() {
    let dir = scratch();
    let src = repo().join("fixtures/csci520/chain");
    for entry in std::fs::read_dir(&src).unwrap() {
        let entry = entry.unwrap();
        std::fs::copy(entry.path(), dir.path().join(entry.file_name())).unwrap();
    }
    std::fs::remove_file(dir.path().join("jointWeights.txt")).unwrap();
    let cfg = dir.path().join("skin.config");
    let out = dir.path().join("chain.glb");
    let without = rigport_ok(&["convert", s(&cfg), "-o", s(&out)]);
    assert!(
        without.contains("W004") && without.contains("--weights auto"),
        "{without}"
    );
    let with = rigport_ok(&["convert", s(&cfg), "--weights", "auto", "-o", s(&out)]);
    assert!(
        !with.contains("W004"),
        "the weights are computed, nothing is lost: {with}"
    );
    assert!(with.contains("bone heat"), "{with}");
    assert_valid(&out);
    let scene = gltf_read::read(&out);
    assert_eq!(scene.skins.len(), 1);
    for row in &scene.skins[0].influences {
        let sum: f32 = row.iter().map(|(_, w)| w).sum();
        assert!((sum - 1.0).abs() < 1e-5, "{row:?}");
    }
    let npz = dir.path().join("chain.npz");
    rigport_ok(&["eval", s(&cfg), "--weights", "auto", "-o", s(&npz), "-q"]);
}

/// A capped-open tube along +Y from 0 to 3 of `rings` rings of `around` vertices, as OBJ
/// text, and a Pinocchio skeleton.out of three joints up its axis (two bones).
fn long_tube(rings: usize, around: usize) -> (String, &'static str) {
    let mut obj = String::new();
    for r in 0..rings {
        let y = 3.0 * r as f32 / (rings - 1) as f32;
        for k in 0..around {
            let t = k as f32 * std::f32::consts::TAU / around as f32;
            writeln!(obj, "v {} {y} {}", 0.2 * t.cos(), 0.2 * t.sin()).unwrap();
        }
    }
    for r in 0..rings - 1 {
        for k in 0..around {
            let v = |r: usize, k: usize| 1 + r * around + k % around;
            let (a0, a1, b0, b1) = (v(r, k), v(r, k + 1), v(r + 1, k), v(r + 1, k + 1));
            writeln!(obj, "f {a0} {b1} {a1}\nf {a0} {b0} {b1}").unwrap();
        }
    }
    (obj, "0 0 0.1 0 -1\n1 0 1.5 0 0\n2 0 2.9 0 1\n")
}

/// Runs `rigport args` under a pseudo-terminal (`script`, util-linux), where progress is
/// drawn: everything the terminal received.
fn on_a_terminal(args: &[&str]) -> String {
    let line = std::iter::once(env!("CARGO_BIN_EXE_rigport"))
        .chain(args.iter().copied())
        .map(|a| format!("'{a}'"))
        .collect::<Vec<_>>()
        .join(" ");
    let out = std::process::Command::new("script")
        .args(["-qefc", &line, "/dev/null"])
        .output()
        .expect("script (util-linux) runs");
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(out.status.success(), "{line}:\n{text}");
    text
}

#[test]
fn meshes_over_50k_vertices_show_a_progress_bar_while_weighted() {
    let dir = scratch();
    let skeleton = dir.path().join("skeleton.out");
    for (name, rings, bar) in [("big", 1601, true), ("small", 101, false)] {
        // 32 around: 51,232 vertices for the big tube, 3,232 for the small one.
        let (obj, bones) = long_tube(rings, 32);
        std::fs::write(&skeleton, bones).unwrap();
        let mesh = dir.path().join(format!("{name}.obj"));
        std::fs::write(&mesh, obj).unwrap();
        let out = dir.path().join(format!("{name}.out"));
        let shown = on_a_terminal(&["skin", s(&mesh), s(&skeleton), "-o", s(&out)]);
        // The bar counts three units per vertex (sight, factorization, solves); a smaller
        // mesh has the step's spinner only.
        let counted = shown.contains(&format!("/{}, ETA", 3 * rings * 32));
        assert_eq!(counted, bar, "{name}:\n{shown}");
        assert!(
            shown.contains("computing weights by bone heat"),
            "{name}:\n{shown}"
        );
        assert!(shown.contains("wrote "), "{name}:\n{shown}");
        let rows = std::fs::read_to_string(&out).unwrap();
        assert_eq!(rows.lines().count(), rings * 32);
    }
}
