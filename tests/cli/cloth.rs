//! `rigport cloth` (issue 18): the USTC course's arm with its cloth to .usda and .glb
//! (validators clean, pinned vertices on the skin in every frame as UsdSkel and three.js
//! evaluate the files, three.js playing what rigport simulated, same bytes every run), and
//! the demo's skirt for 10 s at 60 fps (no NaN, stretch, energy, penetration); a flag on
//! the hand-written arm fixture rendered at two times (body and moving garment drawn), the
//! same bytes with 1 and 3 rayon threads, and bad input (no pins, NaN, a garment starting
//! inside the body) refused or warned about.

use std::path::Path;

use rigport_deform::cloth::attach::nearest_point;
use rigport_deform::cloth::{simulate, ClothOptions, Garment};
use rigport_model::glam::Vec3;

use crate::common::*;
use crate::frames::{diagonal, usd_world};
use crate::render::Picture;
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
    // The garment `rigport demo` simulates (skirt.glb), on its clip, looped to 10 s.
    let (mesh, pins) = rigport_demo::skirt::demo_skirt(&asset);
    let garment = Garment::from_mesh(&asset, &mesh, &[pins]).unwrap();
    let mut warnings = Vec::new();
    let opts = ClothOptions {
        clip: Some(rigport_demo::skirt::CLIP),
        fps: Some(60.0),
        seconds: Some(10.0),
        ..ClothOptions::default()
    };
    let started = std::time::Instant::now();
    let sim = simulate(&asset, &garment, &opts, &mut warnings, |_, _| {}).unwrap();
    let elapsed = started.elapsed().as_secs_f32();
    assert_eq!(sim.times.len(), 601, "10 s at 60 fps, both ends");
    assert!(warnings.is_empty(), "{warnings:?}");
    assert!(
        sim.positions.iter().all(|p| p.is_finite()),
        "a NaN position"
    );
    let worst = sim.worst();
    let argmax = |f: fn(&rigport_deform::cloth::FrameStats) -> f32| {
        sim.stats.iter().enumerate().fold(
            (0, 0.0f32),
            |a, (i, s)| if f(s) > a.1 { (i, f(s)) } else { a },
        )
    };
    let (fs, _) = argmax(|s| s.max_stretch);
    let (fe, _) = argmax(|s| s.kinetic_energy);
    let (fd, _) = argmax(|s| s.max_depth);
    let (fb, _) = argmax(|s| s.body_depth);
    eprintln!(
        "demo skirt on {:?}, 10 s at 60 fps x {} substeps, {} particles ({} pinned), {} capsules, simulated in {elapsed:.1} s: max edge stretch {:.3}% (frame {fs}), max kinetic energy {:.4} m²/s² per kg (frame {fe}), deepest garment vertex {:.2e} m inside a capsule (frame {fd}; thickness {:.4} m), colliding particles at most {:.2e} m inside the grown capsules; at most {} vertices inside the body surface, deepest {:.2e} m (frame {fb})",
        opts.clip.unwrap_or_default(),
        sim.substeps,
        sim.particles,
        sim.pins.len(),
        sim.capsules.len(),
        100.0 * worst.max_stretch,
        worst.kinetic_energy,
        worst.max_depth,
        sim.thickness,
        worst.max_penetration,
        worst.body_inside,
        worst.body_depth,
    );
    for (f, s) in sim.stats.iter().enumerate() {
        // Edge stretch at most 10% in every frame.
        assert!(s.max_stretch <= 0.10, "frame {f}: {s:?}");
        // No garment vertex (pins included) inside a collider by more than the thickness,
        // nor inside the body surface.
        assert!(s.max_depth <= sim.thickness, "frame {f}: {s:?}");
        assert!(s.body_depth <= sim.thickness, "frame {f}: {s:?}");
        // Bounded: no frame's energy is more than what a fall from the waist to the floor
        // would give (g h, h = 1 m).
        assert!(s.kinetic_energy < 9.81, "frame {f}: {s:?}");
    }
    // Not growing either: the last 2 s (one loop of the clip) hold no more energy than the
    // first loop's worst.
    let loop_frames = 120;
    let first = sim.stats[..=loop_frames]
        .iter()
        .map(|s| s.kinetic_energy)
        .fold(0.0, f32::max);
    let last = sim.stats[sim.stats.len() - loop_frames..]
        .iter()
        .map(|s| s.kinetic_energy)
        .fold(0.0, f32::max);
    eprintln!("max kinetic energy: first 2 s {first:.4}, last 2 s {last:.4}");
    // The pre-roll settles the skirt before frame 0, so the first loop holds no fall: its
    // energy is the wave's own, and the last loop's may differ from it by rounding-level
    // amounts (0.00252 and 0.00256 m²/s²); growth would be orders more.
    assert!(
        last <= 1.05 * first.max(1e-3),
        "energy grows: {first} then {last}"
    );
}

/// The hand-written arm fixture (a flat sleeve at z = 1 along +Y, the elbow at y = 2
/// bending 90 deg about Z in its first 33 ms).
const FIXTURE_ARM: &str = "fixtures/usda/skinned_arm.usda";

/// A 5 x 5 flag in the sleeve's plane (z = 1) out from its x = 1 edge over the forearm, 0.25
/// apart (vertex `5 r + c` at `x = 1 + 0.25 c`, `y = 3 + 0.25 r`); the column on the edge
/// (vertices 0, 5, 10, 15, 20) is the one to pin. `inside`: vertex 12 moved inside the
/// sleeve's collision capsules (near the bone axis at x = z = 0).
fn flag_obj(path: &Path, inside: bool) {
    use std::fmt::Write as _;
    let mut text = String::from("# a flag for rigport cloth\n");
    for r in 0..5 {
        for c in 0..5 {
            let (mut x, y, mut z) = (1.0 + 0.25 * c as f32, 3.0 + 0.25 * r as f32, 1.0);
            if inside && r * 5 + c == 12 {
                (x, z) = (0.05, 0.05);
            }
            writeln!(text, "v {x} {y} {z}").unwrap();
        }
    }
    for r in 0..4 {
        for c in 0..4 {
            let a = r * 5 + c + 1;
            writeln!(text, "f {a} {} {}", a + 1, a + 6).unwrap();
            writeln!(text, "f {a} {} {}", a + 6, a + 5).unwrap();
        }
    }
    std::fs::write(path, text).unwrap();
}

/// `rigport cloth` on the fixture arm with `garment`, pinned on the sleeve's edge, 1 s
/// (the clip looped), into `out`, with `threads` rayon threads; returns the process output.
fn cloth_on_fixture(
    garment: &Path,
    out: &Path,
    threads: &str,
    extra: &[&str],
) -> std::process::Output {
    let arm = repo().join(FIXTURE_ARM);
    let mut args = vec![
        "cloth",
        arm.to_str().unwrap(),
        "--garment",
        garment.to_str().unwrap(),
        "--pin-vertices",
        "0,5,10,15,20",
        "--seconds",
        "1",
        "-o",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    std::process::Command::new(env!("CARGO_BIN_EXE_rigport"))
        .args(&args)
        .env("RAYON_NUM_THREADS", threads)
        .output()
        .unwrap()
}

/// Pixels of a renderer picture drawn in a shade of mesh colour `k` (no material: mesh
/// `i` uses `MESH_COLORS[i % 4]`, shaded to the fixed palette).
fn mesh_pixels(pic: &Picture, x0: usize, w: usize, k: usize) -> Vec<(usize, usize)> {
    let levels = rigport_render::SHADE_LEVELS;
    let shades: Vec<[u8; 4]> =
        rigport_render::palette()[4 + k * levels..4 + (k + 1) * levels].to_vec();
    (0..pic.height)
        .flat_map(|y| (x0..x0 + w).map(move |x| (x, y)))
        .filter(|&(x, y)| {
            let i = (y * pic.width + x) * 4;
            shades.iter().any(|s| pic.rgba[i..i + 4] == s[..])
        })
        .map(|(x, y)| (x - x0, y))
        .collect()
}

#[test]
fn render_draws_the_body_and_the_garment_moving_with_the_clip() {
    let dir = scratch();
    let obj = dir.path().join("flag.obj");
    flag_obj(&obj, false);
    let glb = dir.path().join("flag.glb");
    let o = cloth_on_fixture(&obj, &glb, "2", &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_valid(&glb);
    // Two times through one camera: a contact sheet of t = 0 s and t = 1 s side by side.
    let png = dir.path().join("sheet.png");
    rigport_ok(&[
        "render",
        glb.to_str().unwrap(),
        "--fps",
        "1",
        "--size",
        "160x160",
        "--no-skeleton",
        "--no-frame-counter",
        "-o",
        png.to_str().unwrap(),
    ]);
    let pic = Picture::read(&png);
    assert_eq!(
        (pic.width, pic.height),
        (320, 160),
        "two frames side by side"
    );
    let body: Vec<usize> = (0..2)
        .map(|k| mesh_pixels(&pic, 160 * k, 160, 0).len())
        .collect();
    let cloth: Vec<Vec<(usize, usize)>> =
        (0..2).map(|k| mesh_pixels(&pic, 160 * k, 160, 1)).collect();
    eprintln!(
        "body pixels {body:?}, garment pixels {:?}",
        cloth.iter().map(Vec::len).collect::<Vec<_>>()
    );
    assert!(
        body.iter().all(|&n| n > 100),
        "the sleeve is drawn: {body:?}"
    );
    assert!(
        cloth.iter().all(|c| c.len() > 100),
        "the flag is drawn at both times"
    );
    // The flag moved: its pixels at 1 s are not those at 0 s.
    let moved = cloth[1].iter().filter(|p| !cloth[0].contains(p)).count();
    eprintln!("garment pixels at 1 s not covered at 0 s: {moved}");
    assert!(moved > cloth[1].len() / 4, "{moved} of {}", cloth[1].len());
}

#[test]
fn same_bytes_with_1_and_3_threads() {
    let dir = scratch();
    let obj = dir.path().join("flag.obj");
    flag_obj(&obj, false);
    for ext in ["glb", "usda"] {
        let out = |t: &str| dir.path().join(format!("flag{t}.{ext}"));
        for t in ["1", "3"] {
            let o = cloth_on_fixture(&obj, &out(t), t, &["-q"]);
            assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        }
        assert_eq!(
            std::fs::read(out("1")).unwrap(),
            std::fs::read(out("3")).unwrap(),
            "{ext} differs between RAYON_NUM_THREADS=1 and 3"
        );
    }
}

#[test]
fn bad_cloth_input_is_refused_or_warned_about_never_written_as_nan() {
    let dir = scratch();
    let obj = dir.path().join("flag.obj");
    flag_obj(&obj, false);
    let out = dir.path().join("x.glb");
    let stderr = |o: &std::process::Output| String::from_utf8_lossy(&o.stderr).into_owned();
    // No pins.
    let arm = repo().join(FIXTURE_ARM);
    let o = rigport(&[
        "cloth",
        arm.to_str().unwrap(),
        "--garment",
        obj.to_str().unwrap(),
        "--pin-above",
        "100",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("has no pinned vertex"),
        "{}",
        stderr(&o)
    );
    assert!(!out.exists());
    // NaN in the garment, and NaN options.
    let nan = dir.path().join("nan.obj");
    let text = std::fs::read_to_string(&obj)
        .unwrap()
        .replacen("v 1 3 1", "v nan 3 1", 1);
    std::fs::write(&nan, text).unwrap();
    let o = cloth_on_fixture(&nan, &out, "2", &[]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("nan.obj:2:3: coordinate \"nan\" is not finite"),
        "{}",
        stderr(&o)
    );
    // The library refuses a NaN thickness; a NaN frame rate is refused by the CLI's one
    // frame-rate check before any work (exit 2, naming the flag).
    let o = cloth_on_fixture(&obj, &out, "2", &["--thickness", "NaN"]);
    assert!(!o.status.success(), "--thickness NaN");
    assert!(
        stderr(&o).contains("cloth option thickness = NaN"),
        "{}",
        stderr(&o)
    );
    let o = cloth_on_fixture(&obj, &out, "2", &["--fps", "NaN"]);
    assert_eq!(o.status.code(), Some(2), "--fps NaN");
    assert!(
        stderr(&o).contains("'--fps <F>': expected a positive frame rate"),
        "{}",
        stderr(&o)
    );
    assert!(!out.exists());
    // A garment starting inside the body: a warning, then pushed out, finite output.
    let inside = dir.path().join("inside.obj");
    flag_obj(&inside, true);
    let o = cloth_on_fixture(&inside, &out, "2", &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("1 garment vertices start inside the body's collision capsules"),
        "{}",
        stderr(&o)
    );
    assert_valid(&out);
    let (doc, buffers, _) = gltf::import(&out).unwrap();
    for mesh in doc.meshes() {
        for prim in mesh.primitives() {
            let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
            assert!(reader
                .read_positions()
                .unwrap()
                .flatten()
                .all(f32::is_finite));
            for (_, pos, _) in reader.read_morph_targets() {
                if let Some(pos) = pos {
                    assert!(pos.flatten().all(f32::is_finite), "a NaN morph delta");
                }
            }
        }
    }
}
