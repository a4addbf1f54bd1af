//! `rigport cloth` (issue 18): the USTC course's arm with its cloth to .usda and .glb
//! (validators clean, pinned vertices on the skin in every frame as UsdSkel and three.js
//! evaluate the files, three.js playing what rigport simulated, same bytes every run), and
//! the demo's skirt for 10 s at 60 fps (no NaN, stretch, energy, penetration).

use std::path::Path;

use rigport_eval::cloth::attach::nearest_point;
use rigport_eval::cloth::{simulate, ClothOptions, Garment, PinSelection};
use rigport_model::glam::Vec3;

use crate::common::*;
use crate::frames::{diagonal, usd_world};
use crate::three::three_eval;
use crate::usd::{check_usd, python};

const ARM: &str = "6_usd/ustc_cg_24_hw10__USTC-CG/arm_with_cloth.usda";

/// The Grid's pinned vertices: its `primvars:ControlPoints` is 1 at 21 and 23.
const PINS: [usize; 2] = [21, 23];

/// The arm's clip: time codes 1 to 40 at 24 per second.
fn arm_seconds() -> Vec<f64> {
    (1..=40).map(|k| f64::from(k) / 24.0).collect()
}

/// Triangles and vertex counts of the meshes named `body` and `garment` in a glb.
fn glb_meshes(glb: &Path) -> (Vec<[u32; 3]>, usize, usize) {
    let (doc, buffers, _) = gltf::import(glb).unwrap();
    let mut tris = Vec::new();
    let (mut body_n, mut garment_n) = (0, 0);
    for mesh in doc.meshes() {
        for prim in mesh.primitives() {
            let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
            let n = reader.read_positions().unwrap().count();
            match mesh.name() {
                Some("Mesh") => {
                    body_n = n;
                    let ix: Vec<u32> = reader.read_indices().unwrap().into_u32().collect();
                    tris = ix.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect();
                }
                Some("Grid") => garment_n = n,
                _ => {}
            }
        }
    }
    (tris, body_n, garment_n)
}

/// Over all frames (body then garment points, frame-major), the largest distance between a
/// pinned garment vertex and the body point it is bound to, the binding being the nearest
/// surface point at the first frame.
fn pin_error(frames: &[Vec<[f64; 3]>], tris: &[[u32; 3]], body_n: usize) -> f64 {
    let v3 = |p: &[f64; 3]| Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32);
    let first: Vec<Vec3> = frames[0][..body_n].iter().map(v3).collect();
    let mut worst = 0.0f64;
    for &pin in &PINS {
        let (sp, d) = nearest_point(v3(&frames[0][body_n + pin]), &first, tris).unwrap();
        worst = worst.max(f64::from(d));
        for frame in frames {
            let mut bound = [0.0f64; 3];
            for (k, &v) in sp.triangle.iter().enumerate() {
                for c in 0..3 {
                    bound[c] += f64::from(sp.bary[k]) * frame[v as usize][c];
                }
            }
            let g = frame[body_n + pin];
            let d = (0..3)
                .map(|c| (g[c] - bound[c]).powi(2))
                .sum::<f64>()
                .sqrt();
            worst = worst.max(d);
        }
    }
    worst
}

#[test]
fn arm_with_cloth_validates_pins_follow_the_skin_and_three_plays_the_simulation() {
    let Some(arm) = corpus(ARM) else {
        return;
    };
    let dir = scratch();
    let arm = arm.to_str().unwrap();
    let out = |name: &str| dir.path().join(name);
    for name in ["arm.usda", "arm.glb", "again.usda", "again.glb"] {
        rigport_ok(&[
            "cloth",
            "-q",
            arm,
            "--garment",
            "Grid",
            "-o",
            out(name).to_str().unwrap(),
        ]);
    }
    // Determinism: two runs, same bytes.
    for (a, b) in [("arm.usda", "again.usda"), ("arm.glb", "again.glb")] {
        assert_eq!(
            std::fs::read(out(a)).unwrap(),
            std::fs::read(out(b)).unwrap(),
            "{a}"
        );
    }
    let glb = out("arm.glb");
    let usda = out("arm.usda");
    assert_valid(&glb);
    let text = std::fs::read_to_string(&usda).unwrap();
    assert!(
        text.contains("point3f[] points.timeSamples = {"),
        "a point cache"
    );
    assert!(
        !text.contains("def BlendShape"),
        "no blend shapes for the garment"
    );

    let (tris, body_n, garment_n) = glb_meshes(&glb);
    assert_eq!((body_n, garment_n), (12, 25));
    let seconds = arm_seconds();
    let times: Vec<String> = seconds.iter().map(|t| format!("{t}")).collect();

    let three = three_eval(&glb, &["--clip", "Anim", "--times", &times.join(",")]);
    let usd = python().map(|py| {
        let (ok, log) = check_usd(&py, &usda, None);
        assert!(ok, "check_usd: {log}");
        usd_world(&py, &usda, Some(&seconds), None)
    });
    let mut usd_frames = None;
    if let Some(frames) = usd {
        let pts: Vec<Vec<[f64; 3]>> = frames.into_iter().map(|f| f.points).collect();
        assert_eq!(pts[0].len(), body_n + garment_n);
        let diag = diagonal(&pts[0][..body_n]);
        let err = pin_error(&pts, &tris, body_n);
        eprintln!("UsdSkel: pinned vertices off their skin points by at most {err:.3e} ({:.3e} of the diagonal)", err / diag);
        assert!(err <= 1e-5 * diag, "{err} vs diagonal {diag}");
        usd_frames = Some(pts);
    }
    if let Some((report, npy)) = three {
        let meshes = report["meshes"].as_array().unwrap();
        let offset = |skinned: bool| {
            let m = meshes.iter().find(|m| m["skinned"] == skinned).unwrap();
            m["offset"].as_u64().unwrap() as usize
        };
        let (body_off, garment_off) = (offset(true), offset(false));
        let total = npy.shape[1];
        let frames: Vec<Vec<[f64; 3]>> = npy
            .numbers
            .chunks_exact(total * 3)
            .map(|f| {
                let p = |v: usize| [f[3 * v], f[3 * v + 1], f[3 * v + 2]];
                (0..body_n)
                    .map(|v| p(body_off + v))
                    .chain((0..garment_n).map(|v| p(garment_off + v)))
                    .collect()
            })
            .collect();
        assert_eq!(frames.len(), seconds.len());
        let diag = diagonal(&frames[0][..body_n]);
        let err = pin_error(&frames, &tris, body_n);
        eprintln!("three.js: pinned vertices off their skin points by at most {err:.3e} ({:.3e} of the diagonal)", err / diag);
        assert!(err <= 1e-5 * diag, "{err} vs diagonal {diag}");
        // What three.js plays is what rigport simulated (the .usda's point samples).
        if let Some(usd) = &usd_frames {
            let mut worst = 0.0f64;
            for (a, b) in frames.iter().zip(usd) {
                for v in body_n..body_n + garment_n {
                    let d = (0..3)
                        .map(|c| (a[v][c] - b[v][c]).powi(2))
                        .sum::<f64>()
                        .sqrt();
                    worst = worst.max(d);
                }
            }
            eprintln!(
                "three.js vs rigport's simulation: {worst:.3e} ({:.3e} of the diagonal)",
                worst / diag
            );
            assert!(worst <= 1e-4 * diag, "{worst} vs diagonal {diag}");
        }
    }
}

#[test]
fn bad_pins_are_refused() {
    let Some(arm) = corpus(ARM) else {
        return;
    };
    let dir = scratch();
    let out = dir.path().join("x.glb");
    let run = |extra: &[&str]| {
        let mut args = vec!["cloth", arm.to_str().unwrap(), "-o", out.to_str().unwrap()];
        args.extend_from_slice(extra);
        rigport(&args)
    };
    let o = run(&["--garment", "Grid", "--pin-vertices", "99"]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("pinned vertex 99 is out of range"));
    let o = run(&["--garment", "Nope"]);
    assert!(String::from_utf8_lossy(&o.stderr).contains("no unskinned mesh named \"Nope\""));
    assert!(!out.exists());
}

#[test]
fn demo_skirt_for_10_seconds_at_60_fps_is_stable() {
    let demo = rigport_demo::build(1).unwrap();
    let asset = demo.asset;
    let segments = 48;
    let mesh = rigport_demo::skirt::skirt(&asset, 12, segments);
    let pins = PinSelection::Vertices((0..segments).collect());
    let garment = Garment::from_mesh(&asset, &mesh, &[pins]).unwrap();
    let mut warnings = Vec::new();
    let opts = ClothOptions {
        clip: Some("wave"),
        fps: Some(60.0),
        seconds: Some(10.0),
        ..ClothOptions::default()
    };
    let sim = simulate(&asset, &garment, &opts, &mut warnings, |_, _| {}).unwrap();
    assert_eq!(
        sim.times.len(),
        (60.0 * opts.seconds.unwrap()).round() as usize + 1
    );
    assert!(sim.positions.iter().all(|p| p.is_finite()));
    let worst = sim.worst();
    eprintln!(
        "demo skirt, 10 s at 60 fps x {} substeps, {} particles: max stretch {:.3}%, max kinetic energy {:.4} m²/s² per kg, max penetration {:.2e} m (thickness {:.4} m); warnings {warnings:?}",
        sim.substeps,
        sim.particles,
        100.0 * worst.max_stretch,
        worst.kinetic_energy,
        worst.max_penetration,
        sim.thickness
    );
    let (f, s) = sim.stats.iter().enumerate().fold((0, 0.0f32), |a, (f, s)| {
        if s.max_stretch > a.1 {
            (f, s.max_stretch)
        } else {
            a
        }
    });
    eprintln!("worst stretch at frame {f}: {:.3}%", 100.0 * s);
    assert!(worst.max_stretch <= 0.10, "{worst:?}");
    assert!(worst.max_penetration <= sim.thickness, "{worst:?}");
    // Bounded: no frame's energy is more than what a fall from the waist to the floor
    // would give (g h, h = 1 m), let alone growing.
    assert!(worst.kinetic_energy < 9.81, "{worst:?}");
}
