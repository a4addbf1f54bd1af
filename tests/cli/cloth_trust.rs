//! `rigport cloth` says so when its result is wrong (issue 28): after the pre-roll frame 0
//! is settled (stretch under 5%), no garment vertex is inside the body surface deeper
//! than the thickness on any frame, and the energy stays bounded, on the USTC course's
//! arm and on the demo's skirt walking (the corpus's three walks retargeted onto the demo
//! character; on the two CMU walks the hands dip into the skirt past the thickness, see
//! `WALKS`); a time step 10 times too large is an error naming the frame (exit 1), or a
//! W007 warning under `--allow-unstable`.

use std::path::{Path, PathBuf};

use rigport_deform::cloth::{simulate, ClothOptions, Garment, Simulation, GRAVITY};

use crate::common::*;

const ARM: &str = "6_usd/ustc_cg_24_hw10__USTC-CG/arm_with_cloth.usda";

/// Bandai Namco's walk: 1 s at 30 fps.
const BANDAI_WALK: &str = "4_bvh/bandai_namco_ds1/dataset-1_walk_normal_002.bvh";

/// The cgspeed release of a CMU walk: 344 frames at 120 fps, the first a T-pose.
const CGSPEED_WALK: &str = "4_bvh/cmu_cgspeed__nobuyuki83_delfem2/walk.bvh";

/// The corpus's walks: a label, the files `retarget` reads, the frames simulated, the
/// cuts found (`cloth::Cut`: the cgspeed file's T-pose on frame 0).
///
/// On the two CMU walks the arms hang beside the skirt's flare and the hands swing into
/// it: they push it softly (`rigport_deform::cloth` `region`), and no vertex goes deeper
/// than the thickness on any walk.
const WALKS: &[(&str, &[&str], usize, &[usize])] = &[
    ("the Bandai walk", &[BANDAI_WALK], 31, &[]),
    ("the cgspeed walk", &[CGSPEED_WALK], 344, &[1]),
    (
        "the CMU 07_05 walk",
        &[
            "3_acclaim_asf_amc/usc_csci520_mocapPlayer__shreyabhaumik/07-walk.asf",
            "3_acclaim_asf_amc/usc_csci520_mocapPlayer__shreyabhaumik/07_05-walk.amc",
        ],
        517,
        &[],
    ),
];

/// The hand-written arm fixture (a flat sleeve whose elbow bends 90 degrees in 33 ms).
const FIXTURE_ARM: &str = "fixtures/usda/skinned_arm.usda";

/// Runs `rigport` and asserts success, returning stdout.
fn stdout_of(args: &[&str]) -> String {
    let out = rigport(args);
    assert!(
        out.status.success(),
        "rigport {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

/// The acceptance of one run: frame 0 settled, no vertex deeper than the thickness, no edge stretched past 10%, and a kinetic energy per unit mass under what
/// a fall through the body's whole diagonal gives (`g × diagonal`, `gravity` in model
/// units/s²).
fn assert_trusted(label: &str, frames: &[serde_json::Value], thickness: f64, bound: f64) {
    let num = |f: &serde_json::Value, k: &str| f[k].as_f64().unwrap();
    let first = num(&frames[0], "max_stretch");
    let (mut depth, mut energy, mut stretch) = (0.0f64, 0.0f64, 0.0f64);
    for (i, f) in frames.iter().enumerate() {
        depth = depth.max(num(f, "penetration_depth"));
        energy = energy.max(num(f, "kinetic_energy"));
        stretch = stretch.max(num(f, "max_stretch"));
        assert!(
            num(f, "penetration_depth") <= thickness,
            "{label}: frame {i}: {f} (thickness {thickness})"
        );
        assert!(num(f, "kinetic_energy") < bound, "{label}: frame {i}: {f}");
        assert!(num(f, "max_stretch") < 0.1, "{label}: frame {i}: {f}");
    }
    eprintln!(
        "{label}: frame-0 stretch {:.2}%, max stretch {:.2}%, deepest vertex inside the body {depth:.2e} (thickness {thickness:.4}), max kinetic energy {energy:.4} (bound {bound:.1})",
        100.0 * first,
        100.0 * stretch
    );
    assert!(first < 0.05, "{label}: frame-0 stretch {first}");
}

#[test]
fn arm_with_cloth_settles_stays_outside_and_bounded() {
    let Some(arm) = corpus(ARM) else {
        return;
    };
    let dir = scratch();
    let out = dir.path().join("arm.glb");
    let report = stdout_of(&[
        "cloth",
        arm.to_str().unwrap(),
        "--garment",
        "Grid",
        "--json",
        "-o",
        out.to_str().unwrap(),
    ]);
    let json: serde_json::Value = serde_json::from_str(&report).unwrap();
    let frames = json["frames"].as_array().unwrap();
    assert_eq!(frames.len(), 40);
    let thickness = json["thickness"].as_f64().unwrap();
    let diagonal = json["diagonal"].as_f64().unwrap();
    eprintln!(
        "arm_with_cloth: {} s pre-roll, settle residual {:.3e} units/s",
        json["preroll"],
        json["settle_residual"].as_f64().unwrap()
    );
    // metersPerUnit = 1: gravity is 9.8 units/s².
    assert_trusted("arm_with_cloth", frames, thickness, GRAVITY * diagonal);
}

/// The demo character as a .glb, a walk retargeted onto it, and the demo's skirt
/// simulated on it (the clip once, default options; no warning).
fn skirt_on_the_walk(dir: &Path, walk: &[&Path]) -> Simulation {
    let demo = rigport_demo::build(1).unwrap();
    let glb = dir.join("demo.glb");
    let exported =
        rigport_export::to_glb(&demo.asset, &rigport_export::GltfOptions::default()).unwrap();
    std::fs::write(&glb, exported.glb).unwrap();
    let walked = dir.join("walk.glb");
    let mut args = vec!["retarget", walk[0].to_str().unwrap()];
    for motion in &walk[1..] {
        args.extend(["--motion", motion.to_str().unwrap()]);
    }
    args.extend([
        "--onto",
        glb.to_str().unwrap(),
        "-q",
        "-o",
        walked.to_str().unwrap(),
    ]);
    rigport_ok(&args);
    let asset = rigport_import::gltf::import(&walked).unwrap().asset;
    let (mesh, pins) = rigport_demo::skirt::demo_skirt(&asset);
    let garment = Garment::from_mesh(&asset, &mesh, &[pins]).unwrap();
    let mut warnings = Vec::new();
    let sim = simulate(
        &asset,
        &garment,
        &ClothOptions::default(),
        &mut warnings,
        |_, _| {},
    )
    .unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    sim
}

#[test]
fn demo_skirt_on_the_corpus_walks_settles_stays_outside_and_bounded() {
    for (label, files, frames, cuts) in WALKS {
        let Some(walk) = files.iter().map(|f| corpus(f)).collect::<Option<Vec<_>>>() else {
            return;
        };
        let walk: Vec<&Path> = walk.iter().map(PathBuf::as_path).collect();
        let dir = scratch();
        let sim = skirt_on_the_walk(dir.path(), &walk);
        assert_eq!(sim.times.len(), *frames, "{label}");
        let found: Vec<usize> = sim.cuts.iter().map(|c| c.frame).collect();
        assert_eq!(found, *cuts, "{label}: {:?}", sim.cuts);
        let stats: Vec<serde_json::Value> = sim
            .stats
            .iter()
            .map(|s| {
                serde_json::json!({"max_stretch": s.max_stretch, "kinetic_energy": s.kinetic_energy,
                    "penetration_depth": s.body_depth})
            })
            .collect();
        eprintln!(
            "demo skirt on {label}: settle residual {:.3e} m/s, cuts {:?}",
            sim.settle_residual, sim.cuts
        );
        assert_trusted(
            &format!("demo skirt on {label}"),
            &stats,
            f64::from(sim.thickness),
            GRAVITY * f64::from(sim.diagonal),
        );
    }
}

/// A 5 x 5 flag pinned along the fixture sleeve's edge (as `cloth.rs`'s).
fn flag(path: &Path) {
    use std::fmt::Write as _;
    let mut text = String::new();
    for r in 0..5 {
        for c in 0..5 {
            writeln!(
                text,
                "v {} {} 1",
                1.0 + 0.25 * c as f32,
                3.0 + 0.25 * r as f32
            )
            .unwrap();
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

#[test]
fn a_time_step_10_times_too_large_is_an_error_naming_the_frame() {
    let dir = scratch();
    let obj = dir.path().join("flag.obj");
    flag(&obj);
    let out = dir.path().join("flag.glb");
    let arm = repo().join(FIXTURE_ARM);
    let run = |extra: &[&str]| {
        let mut args = vec![
            "cloth",
            arm.to_str().unwrap(),
            "--garment",
            obj.to_str().unwrap(),
            "--pin-vertices",
            "0,5,10,15,20",
            "-o",
            out.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        rigport(&args)
    };
    // 30 fps: 40 substeps by default; 4 is a time step 10 times too large, and with no
    // pre-roll the garment starts on the bent arm at rest.
    let o = run(&["--preroll", "0", "--substeps", "4"]);
    let stderr = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("the simulation diverged at frame 1 (time 0.033"),
        "{stderr}"
    );
    assert!(stderr.contains("edge stretch reached"), "{stderr}");
    assert!(stderr.contains("--allow-unstable"), "{stderr}");
    assert!(!out.exists(), "nothing written");
    // Kept on request, with a coded warning; --deny-warnings refuses it (exit 4).
    let o = run(&["--preroll", "0", "--substeps", "4", "--allow-unstable"]);
    let stderr = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(o.status.success(), "{stderr}");
    assert!(
        stderr.contains("warning[W007]: cloth: the simulation went past its stability limits"),
        "{stderr}"
    );
    assert!(stderr.contains("first at frame 1"), "{stderr}");
    assert_valid(&out);
    let o = run(&[
        "--preroll",
        "0",
        "--substeps",
        "4",
        "--allow-unstable",
        "--deny-warnings",
    ]);
    assert_eq!(o.status.code(), Some(4));
    // The default time step passes.
    let o = run(&[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

#[test]
fn help_states_the_limits() {
    let help = stdout_of(&["cloth", "--help"]);
    let flat = help.split_whitespace().collect::<Vec<_>>().join(" ");
    for needle in [
        format!(
            "edge stretch {}%",
            100.0 * rigport_deform::cloth::UNSTABLE_STRETCH
        ),
        format!(
            "plus {} body diagonals per second",
            rigport_deform::cloth::UNSTABLE_SPEED
        ),
        format!(
            "+ {} diagonals/s",
            rigport_deform::cloth::UNSTABLE_MEAN_SPEED
        ),
        format!("fading over {} s", rigport_deform::cloth::BODY_MEMORY),
        "--preroll".to_string(),
        "--allow-unstable".to_string(),
    ] {
        assert!(flat.contains(&needle), "{needle:?} not in: {flat}");
    }
}
