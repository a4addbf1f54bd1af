//! `rigport verify` identity on the whole corpus (issue 31): every asset the corpus holds
//! (as `rigport batch` finds them in a folder: `rigport_import::gather`), converted by
//! rigport to `.glb`, `.usda`, `.usdc` and `.usdz`, is verified against its source with
//! `--all-clips --tol 1e-5`: every clip of every asset, in every output format, plays as the
//! source within 1e-5 of its diagonal, but for the few named in [`KNOWN`] with their
//! reason (a reported loss `verify` must find, or float32 rounding on a deep chain).
//!
//! Every influence is kept (`--max-influences 8`: glTF's default of 4 is a reported loss).
//! Two threads share the assets; the whole corpus takes about 25 s in a dev build.

use std::path::PathBuf;
use std::sync::Mutex;

use serde_json::Value;

use crate::common::{corpus_dir, require, rigport, scratch};

/// Conversions that do not play exactly as their source, each for a stated reason: the
/// test holds them to what is said here instead of 1e-5.
enum Known {
    /// A loss `convert` reports (its warning code): `verify` must find it (exit 5).
    Loss(&'static str),
    /// Within this fraction of the diagonal, not 1e-5.
    Within(f64, &'static str),
}

const KNOWN: &[(&str, &str, Known)] = &[
    (
        "testUsdSkelBakeSkinning/dqs.usda",
        "glb",
        Known::Loss("W003: glTF skins linearly; the source's DQS skin is written as LBS"),
    ),
    (
        "anims_with_full_rotations_between_keys.fbx",
        "usd",
        Known::Within(2e-5, FLOAT_CHAIN),
    ),
    (
        "anims_with_full_rotations_between_keys.DAE",
        "usd",
        Known::Within(2e-5, FLOAT_CHAIN),
    ),
];

/// Why the 64-joint chain of equal rotations differs by 1.6e-5 of its diagonal in USD: its
/// key times come back from USD time codes a few `f32` units in the last place off (verify
/// takes such keys as one), and the joints' world matrices at the keys still differ by
/// float rounding that 64 joints in a row add up; each joint's own rotation agrees to
/// 7e-7 radians. The glb agrees within 1e-5. Not explained further.
const FLOAT_CHAIN: &str = "float32 rounding along a 64-joint chain";

/// What `label` converted to `ext` is held to (`None`: identity at 1e-5).
fn known(label: &str, ext: &str) -> Option<&'static Known> {
    KNOWN
        .iter()
        .find(|(file, kind, _)| label.ends_with(file) && ext.starts_with(kind))
        .map(|(_, _, k)| k)
}

#[test]
fn every_corpus_asset_plays_as_its_own_conversion_in_every_format() {
    let Some(root) = require("the corpus", Some(corpus_dir()).filter(|d| d.exists())) else {
        return;
    };
    let assets = rigport_import::gather::assets_in(&root, None).expect("corpus readable");
    assert!(assets.len() > 50, "{} assets", assets.len());
    let dir = scratch();
    let next = Mutex::new(assets.iter().enumerate());
    let failures = Mutex::new(Vec::new());
    let checked = Mutex::new(0usize);
    let work = || loop {
        let Some((i, (main, inputs))) = next.lock().unwrap().next() else {
            return;
        };
        let label = main
            .strip_prefix(&root)
            .unwrap_or(main)
            .display()
            .to_string();
        let own = dir.path().join(i.to_string());
        std::fs::create_dir_all(&own).unwrap();
        for ext in ["glb", "usda", "usdc", "usdz"] {
            let out = own.join(format!("asset.{ext}"));
            let mut args: Vec<String> = vec!["convert".into(), "-q".into()];
            args.extend(inputs.iter().map(|p| p.display().to_string()));
            // Every influence kept (glTF's default is 4 a vertex, a reported loss).
            args.extend(["--max-influences", "8", "-o"].map(String::from));
            args.push(out.display().to_string());
            let converted = rigport(&args.iter().map(String::as_str).collect::<Vec<_>>());
            // The Khronos validator's negative files are refused as bad input (exit 1,
            // tests/cli/bad_input.rs words each); so is a folder with two skeletons.
            let refused = label.contains("validator_negative_tests")
                || label.ends_with("pynocchio_smpl__kulendu/rest.obj");
            if refused && converted.status.code() == Some(1) {
                continue;
            }
            if !converted.status.success() {
                let why = String::from_utf8_lossy(&converted.stderr);
                failures
                    .lock()
                    .unwrap()
                    .push(format!("{label} -> .{ext}: convert: {why}"));
                continue;
            }
            let mut args: Vec<String> = vec!["verify".into(), "-q".into()];
            args.extend(reference_args(main, inputs));
            args.extend([out.display().to_string(), "--json".into()]);
            let tol = match known(&label, ext) {
                Some(Known::Within(tol, _)) => *tol,
                _ => 1e-5,
            };
            args.extend(["--all-clips".into(), "--tol".into(), tol.to_string()]);
            let verified = rigport(&args.iter().map(String::as_str).collect::<Vec<_>>());
            let json: Value = serde_json::from_slice(&verified.stdout).unwrap_or(Value::Null);
            let worst = (json["clips"].as_array().into_iter().flatten())
                .filter_map(|c| c["vertices"]["max_relative"].as_f64())
                .fold(0.0, f64::max);
            let (expected, reason) = match known(&label, ext) {
                Some(Known::Loss(why)) => (5, *why),
                Some(Known::Within(_, why)) => (0, *why),
                None => (0, "identity at 1e-5"),
            };
            if verified.status.code() != Some(expected) {
                let why = String::from_utf8_lossy(&verified.stderr);
                let one_side = ["clips_only_reference", "clips_only_candidate"]
                    .into_iter()
                    .chain(["meshes_only_reference", "meshes_only_candidate"])
                    .chain(["morph_targets_only"])
                    .map(|k| format!("{k} {}", json[k]))
                    .collect::<Vec<_>>()
                    .join(", ");
                failures.lock().unwrap().push(format!(
                    "{label} vs its .{ext} ({reason}): exit {:?} (expected {expected}), worst {worst:.2e}; \
                     {one_side}; {why}",
                    verified.status.code(),
                ));
            }
            *checked.lock().unwrap() += 1;
        }
        std::fs::remove_dir_all(&own).ok();
    };
    std::thread::scope(|s| {
        s.spawn(work);
        work();
    });
    let failures = failures.into_inner().unwrap();
    eprintln!(
        "{} assets, {} conversions verified (at 1e-5 but for KNOWN)",
        assets.len(),
        checked.into_inner().unwrap()
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The reference as `verify` takes it: the file, for a Pinocchio rig (a mesh with its
/// `.out` files) its folder, and for an `.asf` its motions.
fn reference_args(main: &std::path::Path, inputs: &[PathBuf]) -> Vec<String> {
    let text = |p: &std::path::Path| p.display().to_string();
    match main.extension().and_then(|e| e.to_str()) {
        Some("obj") if inputs.len() > 1 => vec![text(main.parent().unwrap_or(main))],
        Some("asf") => std::iter::once(text(main))
            .chain(
                inputs[1..]
                    .iter()
                    .flat_map(|m| ["--motion".into(), text(m)]),
            )
            .collect(),
        _ => vec![text(main)],
    }
}
