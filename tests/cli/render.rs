//! End-to-end tests: pictures (`rigport render`).

use std::path::{Path, PathBuf};

use crate::common::{corpus, rigport, rigport_ok, PINOCCHIO_RIGS};
use crate::motion::{ASF_AMC, BVH};

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

fn demo_glb(dir: &Path) -> PathBuf {
    let demo = dir.join("demo");
    rigport_ok(&["demo", "--no-corpus", "-o", s(&demo)]);
    demo.join("demo.glb")
}

#[test]
fn demo_renders_in_every_view_and_skinning_and_is_deterministic() {
    let dir = tempfile::tempdir().unwrap();
    let glb = demo_glb(dir.path());
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
    let glb = demo_glb(dir.path());
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
