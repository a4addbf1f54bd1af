//! End-to-end tests: pictures (`rigport render`).

use std::path::{Path, PathBuf};

use crate::common::{corpus, repo, rigport, rigport_ok, PINOCCHIO_RIGS};
use crate::motion::{ASF_AMC, BVH};

/// The colour IK targets are drawn in.
pub(crate) const MARKER: [u8; 4] = rigport_render::MARKER_COLOR;

/// The renderer's background colour (rigport_render::BACKGROUND).
pub(crate) const BACKGROUND: [u8; 4] = [38, 41, 48, 255];

/// A decoded RGBA8 picture.
pub(crate) struct Picture {
    pub(crate) width: usize,
    pub(crate) height: usize,
    pub(crate) rgba: Vec<u8>,
}

impl Picture {
    pub(crate) fn read(path: &Path) -> Picture {
        let file = std::fs::File::open(path).unwrap();
        let mut reader = png::Decoder::new(std::io::BufReader::new(file))
            .read_info()
            .unwrap();
        let mut buf = vec![0; reader.output_buffer_size().unwrap()];
        let info = reader.next_frame(&mut buf).unwrap();
        assert_eq!(info.color_type, png::ColorType::Rgba, "{}", path.display());
        assert_eq!(info.bit_depth, png::BitDepth::Eight);
        buf.truncate(info.buffer_size());
        Picture {
            width: info.width as usize,
            height: info.height as usize,
            rgba: buf,
        }
    }

    pub(crate) fn is_background(&self, x: usize, y: usize) -> bool {
        let i = (y * self.width + x) * 4;
        self.rgba[i..i + 4] == BACKGROUND
    }

    /// Share of pixels that are not background.
    pub(crate) fn coverage(&self) -> f64 {
        let n = (0..self.height)
            .flat_map(|y| (0..self.width).map(move |x| (x, y)))
            .filter(|&(x, y)| !self.is_background(x, y))
            .count();
        n as f64 / (self.width * self.height) as f64
    }

    /// The pixels of colour `color`, as `(x, y)`.
    pub(crate) fn pixels_of(&self, color: [u8; 4]) -> Vec<(usize, usize)> {
        (0..self.height)
            .flat_map(|y| (0..self.width).map(move |x| (x, y)))
            .filter(|&(x, y)| {
                let i = (y * self.width + x) * 4;
                self.rgba[i..i + 4] == color
            })
            .collect()
    }

    /// Whether every pixel on the outer border is background.
    pub(crate) fn border_is_clear(&self) -> bool {
        let (w, h) = (self.width, self.height);
        (0..w).all(|x| self.is_background(x, 0) && self.is_background(x, h - 1))
            && (0..h).all(|y| self.is_background(0, y) && self.is_background(w - 1, y))
    }
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Renders `inputs` (plus `extra` options) to a 128x128-per-frame contact sheet in `dir`
/// and checks the silhouette: a sensible share of the picture, not clipped by its border.
fn check_sheet(dir: &Path, label: &str, inputs: &[&str], extra: &[&str]) -> PathBuf {
    let out = dir.join(format!("{label}.png"));
    let mut args = vec!["render"];
    args.extend_from_slice(inputs);
    args.extend_from_slice(&["-o", s(&out), "--size", "128x128"]);
    args.extend_from_slice(extra);
    rigport_ok(&args);
    let pic = Picture::read(&out);
    let cov = pic.coverage();
    assert!(
        (0.02..=0.70).contains(&cov),
        "{label}: silhouette covers {:.1}% of the picture",
        cov * 100.0
    );
    assert!(pic.border_is_clear(), "{label}: the picture is clipped");
    out
}

fn demo_glb() -> PathBuf {
    crate::common::demo_outputs().join("demo.glb")
}

#[test]
fn demo_renders_in_every_view_and_skinning_and_is_deterministic() {
    let dir = tempfile::tempdir().unwrap();
    let glb = demo_glb();
    let first = check_sheet(dir.path(), "demo", &[s(&glb)], &[]);
    for view in ["side", "top", "three-quarter"] {
        check_sheet(
            dir.path(),
            &format!("demo_{view}"),
            &[s(&glb)],
            &["--view", view],
        );
    }
    let both = check_sheet(dir.path(), "demo_both", &[s(&glb)], &["--skinning", "both"]);
    let (a, b) = (Picture::read(&first), Picture::read(&both));
    assert_eq!(b.width, 2 * a.width, "both: LBS and DQS side by side");
    // Without the skeleton there are fewer coloured pixels but still a character.
    let bare = check_sheet(dir.path(), "demo_bare", &[s(&glb)], &["--no-skeleton"]);
    assert_ne!(
        std::fs::read(&bare).unwrap(),
        std::fs::read(&first).unwrap()
    );

    // Deterministic: the same command gives the same bytes, PNG and GIF.
    let again = dir.path().join("again.png");
    rigport_ok(&["render", s(&glb), "-o", s(&again), "--size", "128x128"]);
    assert_eq!(
        std::fs::read(&first).unwrap(),
        std::fs::read(&again).unwrap()
    );
    let gifs: Vec<Vec<u8>> = (0..2)
        .map(|k| {
            let out = dir.path().join(format!("demo{k}.gif"));
            rigport_ok(&[
                "render",
                s(&glb),
                "-o",
                s(&out),
                "--size",
                "96x96",
                "--fps",
                "10",
                "--frames",
                "0..12",
            ]);
            std::fs::read(&out).unwrap()
        })
        .collect();
    assert_eq!(&gifs[0][..6], b"GIF89a");
    assert_eq!(gifs[0], gifs[1]);
    // 12 frames: one Graphic Control Extension (0x21 0xF9 0x04) each, delay 10 cs.
    let gce = gifs[0]
        .windows(3)
        .filter(|w| w == &[0x21, 0xF9, 0x04])
        .count();
    assert_eq!(gce, 12);

    // APNG: five full-colour frames of 100 ms.
    let apng = dir.path().join("demo.apng");
    rigport_ok(&[
        "render",
        s(&glb),
        "-o",
        s(&apng),
        "--size",
        "64x64",
        "--fps",
        "10",
        "--frames",
        "2..7",
    ]);
    let reader = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&apng).unwrap()))
        .read_info()
        .unwrap();
    let info = reader.info();
    assert_eq!(info.animation_control.map(|a| a.num_frames), Some(5));
    let fctl = info.frame_control.unwrap();
    assert_eq!((fctl.delay_num, fctl.delay_den), (100, 1000));
}

#[test]
fn bad_render_arguments_fail_cleanly() {
    let dir = tempfile::tempdir().unwrap();
    let glb = demo_glb();
    for (extra, out, needle) in [
        (&["--clip", "nope"][..], "a.png", "no clip named"),
        (&[][..], "a.bmp", "unknown picture format"),
        (&["--size", "0x10"][..], "a.png", "pixels"),
        (&["--frames", "5..2"][..], "a.png", "empty"),
        (&["--frames", "1000.."][..], "a.png", "keeps no frame"),
        (&["--fps", "0"][..], "a.png", "frame rate"),
    ] {
        let target = dir.path().join(out);
        let mut args = vec!["render", s(&glb), "-o", s(&target)];
        args.extend_from_slice(extra);
        let res = rigport(&args);
        let stderr = String::from_utf8_lossy(&res.stderr);
        assert!(!res.status.success(), "{extra:?} succeeded");
        assert!(stderr.contains(needle), "{extra:?}: {stderr}");
        assert!(!target.exists());
    }
}

#[test]
fn one_corpus_rig_of_each_family_renders_unclipped() {
    let dir = tempfile::tempdir().unwrap();
    let (_, mesh, skel, att) = PINOCCHIO_RIGS[0];
    if let (Some(m), Some(sk), Some(a)) = (corpus(mesh), corpus(skel), corpus(att)) {
        // A rig without clips: its rest pose.
        check_sheet(dir.path(), "pinocchio", &[s(&m), s(&sk), s(&a)], &[]);
    }
    // The CSCI 520 rigs (tests/cli/csci520.rs's first one).
    if let Some(cfg) = corpus("2_csci520_ik_skinning/tydia/armadillo/skin.config") {
        check_sheet(
            dir.path(),
            "csci520",
            &[s(&cfg)],
            &["--view", "three-quarter"],
        );
    }
    let (asf, amc) = ASF_AMC[0];
    if let (Some(asf), Some(amc)) = (corpus(asf), corpus(amc)) {
        check_sheet(dir.path(), "asf_amc", &[s(&asf), s(&amc)], &[]);
    }
    if let Some(bvh) = corpus(BVH[0]) {
        check_sheet(dir.path(), "bvh", &[s(&bvh)], &["--view", "side"]);
    }
    if let Some(gltf) = corpus("5_gltf/khronos_samples__nobuyuki83_delfem2/CesiumMan.glb") {
        check_sheet(dir.path(), "gltf", &[s(&gltf)], &["--skinning", "dqs"]);
    }
}

/// The branch fixture (`fixtures/pinocchio/branch*`): a 2-unit-tall strip in the z = 0
/// plane, x in [-0.1, 0.3], y in [0, 2]; joints `root`, `bone_1` .. `bone_4`.
fn branch_rig() -> Vec<String> {
    ["branch.obj", "branch_skeleton.out", "branch_attachment.out"]
        .iter()
        .map(|f| {
            repo()
                .join("fixtures/pinocchio")
                .join(f)
                .to_string_lossy()
                .into_owned()
        })
        .collect()
}

/// Renders the branch rig to a 128x128 `out` with `extra` options.
fn render_branch(out: &Path, extra: &[&str]) -> Picture {
    let rig = branch_rig();
    let mut args: Vec<&str> = vec!["render"];
    args.extend(rig.iter().map(String::as_str));
    args.extend_from_slice(&["-o", s(out), "--size", "128x128"]);
    args.extend_from_slice(extra);
    rigport_ok(&args);
    Picture::read(out)
}

/// The branch rig's handles: two absolute targets far outside the body and a relative one
/// at `bone_4`'s rest origin (Pinocchio joint 3, the knee at (0.2, 0.5, 0)).
const BRANCH_HANDLES: &str = r#"{"handles": [
  {"joint": "bone_2", "keys": [{"time": 0, "position": [3, 5, 0]}]},
  {"joint": "bone_1", "keys": [{"time": 0, "position": [-3, -3, 0]}]},
  {"joint": "bone_4", "relative": true, "keys": [{"time": 0, "position": [0, 0, 0]}]}
]}"#;

#[test]
fn handles_draw_ik_targets_as_markers_inside_the_picture() {
    let dir = tempfile::tempdir().unwrap();
    let handles = dir.path().join("branch.handles.json");
    std::fs::write(&handles, BRANCH_HANDLES).unwrap();

    let plain = render_branch(&dir.path().join("plain.png"), &[]);
    assert!(
        plain.pixels_of(MARKER).is_empty(),
        "markers without --handles"
    );
    let marked = render_branch(&dir.path().join("marked.png"), &["--handles", s(&handles)]);
    // The targets span x in [-3, 3], y in [-3, 5] and hold the body, so they set the framing:
    // 128 px less 8% on each side is 107.52 px for 8 units, 13.44 px per unit around
    // (0, 1). Expected centres: (64 + 13.44 x, 64 - 13.44 (y - 1)).
    let expected = [(104.32, 10.24), (23.68, 117.76), (66.69, 70.72)];
    let at = marked.pixels_of(MARKER);
    for (cx, cy) in expected {
        let near = at
            .iter()
            .filter(|&&(x, y)| {
                (x as f64 + 0.5 - cx).abs() < 6.0 && (y as f64 + 0.5 - cy).abs() < 6.0
            })
            .count();
        assert!(near >= 12, "{near} marker pixels near ({cx}, {cy})");
    }
    // Nothing else is drawn in the marker colour, and the far targets are not clipped.
    assert!(at.iter().all(|&(x, y)| expected
        .iter()
        .any(|&(cx, cy)| (x as f64 + 0.5 - cx).abs() < 7.0 && (y as f64 + 0.5 - cy).abs() < 7.0)));
    assert!(marked.border_is_clear(), "a target is clipped");
    // Framing on the targets makes the body smaller.
    assert!(marked.coverage() < plain.coverage());

    // Deterministic, also as a GIF (the marker colour is in the fixed palette).
    let again = render_branch(&dir.path().join("again.png"), &["--handles", s(&handles)]);
    assert_eq!(marked.rgba, again.rgba);
    let gif = dir.path().join("marked.gif");
    render_branch_gif(&gif, &handles);
    let mut options = gif::DecodeOptions::new();
    options.set_color_output(gif::ColorOutput::RGBA);
    let mut decoder = options
        .read_info(std::io::BufReader::new(std::fs::File::open(&gif).unwrap()))
        .unwrap();
    let frame = decoder.read_next_frame().unwrap().unwrap();
    assert!(frame.buffer.chunks(4).any(|c| c == MARKER));
}

fn render_branch_gif(out: &Path, handles: &Path) {
    let rig = branch_rig();
    let mut args: Vec<&str> = vec!["render"];
    args.extend(rig.iter().map(String::as_str));
    args.extend_from_slice(&["-o", s(out), "--size", "64x64", "--handles", s(handles)]);
    rigport_ok(&args);
}

#[test]
fn bad_handles_file_fails_with_its_name_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let rig = branch_rig();
    let bad_joint = dir.path().join("bad_joint.json");
    std::fs::write(
        &bad_joint,
        r#"{"handles": [{"joint": "nope", "keys": [{"time": 0, "position": [0, 0, 0]}]}]}"#,
    )
    .unwrap();
    let bad_syntax = dir.path().join("bad_syntax.json");
    std::fs::write(&bad_syntax, "{\"handles\": [\n  {\"joint\": }\n]}").unwrap();
    let missing = dir.path().join("missing.json");
    for (handles, needle) in [
        (&bad_joint, "no joint named \"nope\""),
        (&bad_syntax, "bad_syntax.json:2:"),
        (&missing, "cannot read"),
    ] {
        let out = dir.path().join("out.png");
        let mut args: Vec<&str> = vec!["render"];
        args.extend(rig.iter().map(String::as_str));
        args.extend_from_slice(&["-o", s(&out), "--handles", s(handles)]);
        let res = rigport(&args);
        let stderr = String::from_utf8_lossy(&res.stderr);
        assert_eq!(res.status.code(), Some(1), "{stderr}");
        assert!(stderr.contains(s(handles)), "names the file: {stderr}");
        assert!(stderr.contains(needle), "{needle:?}: {stderr}");
        assert!(!out.exists(), "{} written", out.display());
    }
}

#[test]
fn perspective_render_is_deterministic_and_inside_the_picture() {
    let dir = tempfile::tempdir().unwrap();
    // The flat branch strip seen from three-quarters: its near and far ends are drawn at
    // different scales, so the picture differs from the orthographic one.
    let extra = ["--view", "three-quarter", "--no-skeleton"];
    let ortho = render_branch(&dir.path().join("ortho.png"), &extra);
    let mut persp_args = extra.to_vec();
    persp_args.extend_from_slice(&["--camera", "perspective"]);
    let persp = render_branch(&dir.path().join("persp.png"), &persp_args);
    let again = render_branch(&dir.path().join("again.png"), &persp_args);
    assert_eq!(
        std::fs::read(dir.path().join("persp.png")).unwrap(),
        std::fs::read(dir.path().join("again.png")).unwrap()
    );
    assert_eq!(persp.rgba, again.rgba);
    assert_ne!(persp.rgba, ortho.rgba);
    assert!(persp.border_is_clear());
    let (cp, co) = (persp.coverage(), ortho.coverage());
    assert!(cp > 0.2 * co && cp <= co * 1.05, "{cp} vs {co}");
    // `--camera ortho` is the default: same bytes.
    let mut ortho_args = extra.to_vec();
    ortho_args.extend_from_slice(&["--camera", "ortho"]);
    render_branch(&dir.path().join("ortho2.png"), &ortho_args);
    assert_eq!(
        std::fs::read(dir.path().join("ortho.png")).unwrap(),
        std::fs::read(dir.path().join("ortho2.png")).unwrap()
    );
}

#[test]
fn demo_reach_shows_its_targets_in_every_view_and_camera() {
    let dir = tempfile::tempdir().unwrap();
    let glb = demo_glb();
    let handles = crate::common::demo_outputs().join("reach.handles.json");
    for camera in ["ortho", "perspective"] {
        for view in ["front", "side", "top", "three-quarter"] {
            let label = format!("reach_{camera}_{view}");
            let out = check_sheet(
                dir.path(),
                &label,
                &[s(&glb)],
                &[
                    "--clip",
                    "reach",
                    "--handles",
                    s(&handles),
                    "--camera",
                    camera,
                    "--view",
                    view,
                ],
            );
            // A 4 x 4 sheet of 128 px cells: a marker in every cell.
            let pic = Picture::read(&out);
            let at = pic.pixels_of(MARKER);
            for cell in 0..16 {
                let (cx, cy) = (cell % 4 * 128, cell / 4 * 128);
                assert!(
                    at.iter()
                        .any(|&(x, y)| (cx..cx + 128).contains(&x) && (cy..cy + 128).contains(&y)),
                    "{label}: no marker in cell {cell}"
                );
            }
        }
    }
    let plain = check_sheet(dir.path(), "reach_plain", &[s(&glb)], &["--clip", "reach"]);
    assert!(Picture::read(&plain).pixels_of(MARKER).is_empty());
    // Perspective of a whole character, deterministic.
    let again = dir.path().join("again.png");
    rigport_ok(&[
        "render",
        s(&glb),
        "-o",
        s(&again),
        "--size",
        "128x128",
        "--clip",
        "reach",
        "--handles",
        s(&handles),
        "--camera",
        "perspective",
        "--view",
        "three-quarter",
    ]);
    assert_eq!(
        std::fs::read(dir.path().join("reach_perspective_three-quarter.png")).unwrap(),
        std::fs::read(&again).unwrap()
    );
}

#[test]
fn handles_fixture_on_its_corpus_rig_marks_the_targets() {
    // fixtures/ik/pinocchio_two_hand_reach.json is written for the corpus's Model1.
    let (_, mesh, skel, att) = PINOCCHIO_RIGS[3];
    let (Some(m), Some(sk), Some(a)) = (corpus(mesh), corpus(skel), corpus(att)) else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let handles = repo().join("fixtures/ik/pinocchio_two_hand_reach.json");
    // The IK clip solved for those handles, then its picture with the targets.
    let glb = dir.path().join("reach.glb");
    rigport_ok(&[
        "ik",
        s(&m),
        s(&sk),
        s(&a),
        "--handles",
        s(&handles),
        "-o",
        s(&glb),
    ]);
    let out = check_sheet(
        dir.path(),
        "model1_reach",
        &[s(&glb)],
        &["--handles", s(&handles), "--camera", "perspective"],
    );
    assert!(!Picture::read(&out).pixels_of(MARKER).is_empty());
}

/// The demo's skirt is baked into morph targets (`rigport cloth`); render plays them, as
/// every viewer does. Two frames of the wave, side by side on one sheet (one camera): the
/// wave moves only the arms, so the band where the skirt hangs differs only because the
/// skirt moves (a rigid skirt left it identical).
#[test]
fn render_shows_the_baked_skirt_moving() {
    let dir = tempfile::tempdir().unwrap();
    let demo = crate::common::demo_outputs();
    let png = dir.path().join("skirt.png");
    rigport_ok(&[
        "render",
        s(&demo.join("skirt.glb")),
        "--clip",
        "wave",
        "--fps",
        "1",
        "--frames",
        "0..2",
        "--size",
        "128x128",
        "--no-skeleton",
        "-o",
        s(&png),
    ]);
    let sheet = Picture::read(&png);
    assert_eq!((sheet.width, sheet.height), (256, 128), "two panels");
    let pixel = |x: usize, y: usize| &sheet.rgba[(y * sheet.width + x) * 4..][..4];
    // The skirt's band: from the hips (55% of the height) to above the knees (80%).
    let changed = (70..102)
        .flat_map(|y| (0..128).map(move |x| (x, y)))
        .filter(|&(x, y)| pixel(x, y) != pixel(x + 128, y))
        .count();
    assert!(
        changed > 100,
        "only {changed} pixels of the skirt band change"
    );
}
