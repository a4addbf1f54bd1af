//! Acceptance 5: the demo needs no input and its output validates clean. Issue 8
//! (acceptance 1, 2): the demo's pictures, and one per corpus family, show the character
//! unclipped and are deterministic; the reach picture marks its IK targets. Issue 5: the twisting-limb LBS-vs-DQS comparison and
//! its DQS bake.

use std::path::{Path, PathBuf};

use crate::common::*;
use crate::render::{Picture, BACKGROUND, MARKER};

/// The pictures the demo always writes.
const DEMO_PICTURES: [&str; 5] = [
    "wave.png",
    "reach.png",
    "wave.gif",
    "twist_lbs_vs_dqs.png",
    "skirt.png",
];

/// The corpus pictures the demo writes when the corpus is present, one per family.
const CORPUS_PICTURES: [&str; 6] = [
    "corpus/1_pinocchio.png",
    "corpus/2_csci520_ik_skinning.png",
    "corpus/3_acclaim_asf_amc.png",
    "corpus/4_bvh.png",
    "corpus/5_gltf.png",
    "corpus/6_usd.png",
];

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Runs the demo into `out` (reading the corpus from `corpus`, or with `--no-corpus`).
fn run_demo(out: &Path, corpus: Option<&Path>) -> String {
    let mut args = vec!["demo", "-o", s(out)];
    match corpus {
        Some(c) => args.extend_from_slice(&["--corpus", s(c)]),
        None => args.push("--no-corpus"),
    }
    rigport_ok(&args)
}

/// Every frame of a GIF written by the renderer (full-size frames), as RGBA pictures.
fn gif_frames(path: &Path) -> Vec<Picture> {
    let mut options = gif::DecodeOptions::new();
    options.set_color_output(gif::ColorOutput::RGBA);
    let mut decoder = options
        .read_info(std::io::BufReader::new(std::fs::File::open(path).unwrap()))
        .unwrap();
    let (w, h) = (usize::from(decoder.width()), usize::from(decoder.height()));
    let mut frames = Vec::new();
    while let Some(frame) = decoder.read_next_frame().unwrap() {
        assert_eq!(
            (usize::from(frame.width), usize::from(frame.height)),
            (w, h),
            "{}: the renderer writes full frames",
            path.display()
        );
        frames.push(Picture {
            width: w,
            height: h,
            rgba: frame.buffer.to_vec(),
        });
    }
    frames
}

/// Decodes `path` (PNG or GIF) and checks every picture in it: a silhouette covering a
/// sensible share, clear of the border. Returns the decoded pictures.
fn check_picture(path: &Path) -> Vec<Picture> {
    assert!(path.is_file(), "{} was not written", path.display());
    let pictures = if path.extension().is_some_and(|e| e == "gif") {
        gif_frames(path)
    } else {
        vec![Picture::read(path)]
    };
    assert!(!pictures.is_empty(), "{}: no frames", path.display());
    for (i, pic) in pictures.iter().enumerate() {
        let cov = pic.coverage();
        if i == 0 {
            eprintln!("{}: {:.2}% covered", path.display(), cov * 100.0);
        }
        assert!(
            (0.02..=0.70).contains(&cov),
            "{} frame {i}: silhouette covers {:.2}% of the picture",
            path.display(),
            cov * 100.0
        );
        assert!(
            pic.border_is_clear(),
            "{} frame {i}: the picture is clipped",
            path.display()
        );
    }
    pictures
}

/// Pixels of the left half that differ from the same pixel of the right half, below the
/// band at the top where the renderer names each panel's method ("LBS", "DQS": font rows
/// 2..7 at a scale of height / 128).
fn halves_differ(pic: &Picture) -> usize {
    let half = pic.width / 2;
    let label_band = 8 * (pic.height / 128).max(1);
    let px = |x: usize, y: usize| &pic.rgba[(y * pic.width + x) * 4..(y * pic.width + x) * 4 + 4];
    (label_band..pic.height)
        .flat_map(|y| (0..half).map(move |x| (x, y)))
        .filter(|&(x, y)| px(x, y) != px(x + half, y))
        .count()
}

#[test]
fn demo_writes_a_valid_skinned_glb() {
    let dir = scratch();
    let out = dir.path().join("demo-out");
    let stderr = run_demo(&out, None);
    let glb = out.join("demo.glb");
    assert!(glb.exists(), "no demo.glb; stderr:\n{stderr}");
    assert_valid(&glb);
    let scene = crate::gltf_read::read(&glb);
    assert_eq!(scene.skins.len(), 1);
    assert!(
        scene.skins[0].positions.len() > 2000,
        "{} vertices",
        scene.skins[0].positions.len()
    );
    assert!(scene.skins[0].joints.len() >= 15);
    // Deterministic: a second run writes the same bytes.
    let again = dir.path().join("again");
    rigport_ok(&["demo", "--quiet", "--no-corpus", "-o", s(&again)]);
    assert_eq!(
        std::fs::read(&glb).unwrap(),
        std::fs::read(again.join("demo.glb")).unwrap()
    );
}

#[test]
fn demo_pictures_show_the_character_unclipped_and_are_deterministic() {
    let dir = scratch();
    let corpus_dir = corpus("MANIFEST.tsv").map(|m| m.parent().unwrap().to_path_buf());
    let out = dir.path().join("first");
    run_demo(&out, corpus_dir.as_deref());
    let mut written: Vec<PathBuf> = DEMO_PICTURES.iter().map(|p| out.join(p)).collect();
    for p in &written {
        check_picture(p);
    }
    // The reach sheet shows the IK targets it was solved for; the others have no markers.
    let marked = |name: &str| !Picture::read(&out.join(name)).pixels_of(MARKER).is_empty();
    assert!(marked("reach.png"), "reach.png shows no IK target");
    assert!(!marked("wave.png"));
    let gif = gif_frames(&out.join("wave.gif"));
    // 2 s at 15 fps, both ends included, 256x256.
    assert_eq!(gif.len(), 31);
    assert_eq!((gif[0].width, gif[0].height), (256, 256));

    // The comparison shows something: LBS (left) and DQS (right) of the same frame through
    // the same camera differ where the twisted forearm collapses under LBS, and only there
    // (the rest of the body is identical).
    let twist = Picture::read(&out.join("twist_lbs_vs_dqs.png"));
    assert_eq!(twist.width, 2 * twist.height, "LBS and DQS side by side");
    let differ = halves_differ(&twist);
    let share = differ as f64 / (twist.width / 2 * twist.height) as f64;
    eprintln!("twist: LBS and DQS differ in {differ} pixels");
    assert!(
        differ >= 50 && share < 0.05,
        "LBS and DQS halves differ in {differ} pixels ({:.2}%)",
        share * 100.0
    );
    // Each half shows the whole character.
    for (label, x0) in [("LBS", 0), ("DQS", twist.width / 2)] {
        let half = Picture {
            width: twist.width / 2,
            height: twist.height,
            rgba: (0..twist.height)
                .flat_map(|y| {
                    let i = (y * twist.width + x0) * 4;
                    twist.rgba[i..i + twist.width / 2 * 4].to_vec()
                })
                .collect(),
        };
        let cov = half.coverage();
        assert!(
            (0.02..=0.70).contains(&cov) && half.border_is_clear(),
            "{label} half: {:.2}% covered, border clear: {}",
            cov * 100.0,
            half.border_is_clear()
        );
        assert!(half.is_background(0, 0));
    }

    // The DQS bake of the twist clip: valid glTF with morph targets (one per sampled frame)
    // animated by a weights channel.
    let dqs = out.join("twist_dqs.glb");
    assert_valid(&dqs);
    let (doc, _, _) = gltf::import(&dqs).unwrap();
    let targets: usize = doc
        .meshes()
        .flat_map(|m| m.primitives())
        .map(|p| p.morph_targets().count())
        .max()
        .unwrap_or(0);
    assert_eq!(
        targets, 61,
        "2 s at 30 fps, both ends: one target per frame"
    );
    assert!(doc
        .animations()
        .flat_map(|a| a.channels())
        .any(|c| c.target().property() == gltf::animation::Property::MorphTargetWeights));
    assert_eq!(doc.animations().count(), 1, "the twist clip alone");

    // The skirt (issue 18): valid glTF, the skirt its own unskinned mesh animated by one
    // morph target per frame of the wave clip, and the sheet shows it moving.
    let skirt = out.join("skirt.glb");
    assert_valid(&skirt);
    let (doc, _, _) = gltf::import(&skirt).unwrap();
    let garment = doc
        .meshes()
        .find(|m| m.name() == Some("skirt"))
        .expect("a skirt mesh");
    let prim = garment.primitives().next().unwrap();
    assert_eq!(prim.morph_targets().count(), 61, "2 s at 30 fps, both ends");
    assert!(doc
        .nodes()
        .any(|n| n.mesh().is_some_and(|m| m.index() == garment.index()) && n.skin().is_none()));
    assert_eq!(doc.animations().count(), 1, "the wave clip alone");
    written.push(skirt);

    if corpus_dir.is_some() {
        for p in CORPUS_PICTURES {
            written.push(out.join(p));
            check_picture(&out.join(p));
        }
    }

    // Deterministic: a second run writes the same bytes.
    let again = dir.path().join("again");
    run_demo(&again, corpus_dir.as_deref());
    let root = |p: &Path| p.strip_prefix(&out).unwrap().to_path_buf();
    written.push(dqs);
    for p in &written {
        assert_eq!(
            std::fs::read(p).unwrap(),
            std::fs::read(again.join(root(p))).unwrap(),
            "{} differs between two runs",
            root(p).display()
        );
    }
}

#[test]
fn demo_without_the_corpus_says_so_and_succeeds() {
    let dir = scratch();
    let out = dir.path().join("out");
    let missing = dir.path().join("no-corpus-here");
    let res = rigport(&["demo", "-o", s(&out), "--corpus", s(&missing)]);
    assert!(res.status.success());
    let stdout = String::from_utf8_lossy(&res.stdout);
    let lines: Vec<&str> = stdout.lines().filter(|l| l.contains("corpus")).collect();
    assert_eq!(lines.len(), 1, "{stdout}");
    assert!(lines[0].contains("not found"), "{stdout}");
    assert!(!out.join("corpus").exists());
    // A corpus folder without the expected files: one warning line per family, no failure.
    let empty = dir.path().join("empty-corpus");
    std::fs::create_dir_all(&empty).unwrap();
    let out2 = dir.path().join("out2");
    let stderr = rigport_ok(&["demo", "--quiet", "-o", s(&out2), "--corpus", s(&empty)]);
    let warnings = stderr
        .lines()
        .filter(|l| l.starts_with("warning: corpus"))
        .count();
    assert_eq!(warnings, 6, "{stderr}");
    assert!(out2.join("twist_lbs_vs_dqs.png").is_file());
    // The background colour the pictures are checked against is the renderer's.
    let pic = Picture::read(&out.join("wave.png"));
    assert_eq!(&pic.rgba[0..4], &BACKGROUND);
}
