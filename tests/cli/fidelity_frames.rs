//! The frames and times `fbx_fidelity` compares in: three's FBX / COLLADA loaders' world
//! frames turned into rigport's +Y-up metres (the conversions and why: `fbx_fidelity`'s
//! module doc), and clip times moved onto the time codes UsdSkel evaluates.

use std::path::Path;

use crate::fidelity_match::Points;

/// A linear map from a loader's world frame to rigport's +Y-up metres (rows).
pub type ToModel = [[f64; 3]; 3];

pub fn apply(m: &ToModel, points: &[[f64; 3]]) -> Points {
    points
        .iter()
        .map(|p| [0, 1, 2].map(|r| (0..3).map(|k| m[r][k] * p[k]).sum()))
        .collect()
}

/// ufbx's axis as a unit vector of the file's basis (+X, -X, +Y, -Y, +Z, -Z).
fn axis(a: ufbx::CoordinateAxis) -> [f64; 3] {
    let i = a as usize;
    let mut v = [0.0; 3];
    v[i / 2] = if i % 2 == 0 { 1.0 } else { -1.0 };
    v
}

/// FBXLoader's frame to rigport's (the module doc): `unit_meters * A * R^-1`, A's rows the
/// file's right, up and front axes, R the loader's -90 degree turn about X for UpAxis 2.
pub fn fbx_to_model(file: &Path) -> (ToModel, ufbx::SceneRoot) {
    let scene = ufbx::load_file(file.to_str().unwrap(), ufbx::LoadOpts::default()).unwrap();
    let axes = &scene.settings.axes;
    let a = [axis(axes.right), axis(axes.up), axis(axes.front)];
    let z_up = matches!(
        axes.up,
        ufbx::CoordinateAxis::PositiveZ | ufbx::CoordinateAxis::NegativeZ
    );
    // R^-1 for R = Rx(-90): (x, y, z) -> (x, -z, y).
    let r_inv = if z_up {
        [[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]]
    } else {
        [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
    };
    let s = scene.settings.unit_meters;
    let m = [0, 1, 2]
        .map(|r| [0, 1, 2].map(|c| s * (0..3).map(|k| a[r][k] * r_inv[k][c]).sum::<f64>()));
    (m, scene)
}

/// ColladaLoader's frame to rigport's (the module doc).
pub fn collada_to_model(up_axis: &str) -> ToModel {
    if up_axis == "X_UP" {
        [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
    } else {
        [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
    }
}

/// The `.usda`'s `timeCodesPerSecond`.
pub fn time_codes_per_second(usda: &Path) -> f64 {
    let text = std::fs::read_to_string(usda).unwrap();
    let line = text
        .lines()
        .find_map(|l| l.trim().strip_prefix("timeCodesPerSecond = "))
        .unwrap_or_else(|| panic!("{} states no timeCodesPerSecond", usda.display()));
    line.trim().parse().unwrap()
}

/// `times` moved to where UsdSkel is evaluated (tools/check_usd.py's `time_code`: a time
/// within 1e-3 frames of a whole time code, or 2^-21 of it, is that code), so three.js
/// plays both files at the very times UsdSkel does: on a fast turn 1e-3 frames is 1e-5 of
/// the pose.
pub fn snap(times: &[f64], tcps: f64) -> Vec<f64> {
    times
        .iter()
        .map(|&t| {
            let tc = t * tcps;
            let whole = tc.round();
            if (tc - whole).abs() <= 1e-3f64.max(tc.abs() * 2f64.powi(-21)) {
                whole / tcps
            } else {
                t
            }
        })
        .collect()
}
