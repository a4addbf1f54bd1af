//! Motion (ASF/AMC, BVH, clips, time warping, keyframes) end to end, checked against
//! test-only reference FK written straight from FORMATS.md and a test-only glTF sampler.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use rigport_model::glam::{DMat3, DQuat, DVec3, Mat4, Quat, Vec3};

use crate::common::*;
use crate::gltf_read::{self, GltfScene};

/// The ASF/AMC pairs of the corpus.
pub const ASF_AMC: [(&str, &str); 3] = [
    (
        "3_acclaim_asf_amc/usc_csci520_mocapPlayer__shreyabhaumik/07-walk.asf",
        "3_acclaim_asf_amc/usc_csci520_mocapPlayer__shreyabhaumik/07_05-walk.amc",
    ),
    (
        "3_acclaim_asf_amc/usc_csci520_mocapPlayer__shreyabhaumik/09-run.asf",
        "3_acclaim_asf_amc/usc_csci520_mocapPlayer__shreyabhaumik/09_06-run.amc",
    ),
    (
        "3_acclaim_asf_amc/usc_csci520_mocapPlayer__shreyabhaumik/131-dance.asf",
        "3_acclaim_asf_amc/usc_csci520_mocapPlayer__shreyabhaumik/131_04-dance.amc",
    ),
];

/// The BVH files of the corpus.
pub const BVH: [&str; 4] = [
    "4_bvh/bandai_namco_ds1/dataset-1_walk_normal_002.bvh",
    "4_bvh/bandai_namco_ds1/dataset-1_dash_normal_001.bvh",
    "4_bvh/bandai_namco_ds1/dataset-1_kick_normal_001.bvh",
    "4_bvh/cmu_cgspeed__nobuyuki83_delfem2/walk.bvh",
];

// ---------------------------------------------------------------------------------------
// Reference FK, from FORMATS.md only (f64, recursive, no rigport code).

fn rot(axis: char, angle_rad: f64) -> DMat3 {
    match axis.to_ascii_lowercase() {
        'x' => DMat3::from_rotation_x(angle_rad),
        'y' => DMat3::from_rotation_y(angle_rad),
        'z' => DMat3::from_rotation_z(angle_rad),
        other => panic!("axis {other}"),
    }
}

/// "The first listed axis is applied first": each next rotation multiplies on the left.
fn first_applied_first(axes_and_angles: &[(char, f64)]) -> DMat3 {
    axes_and_angles
        .iter()
        .fold(DMat3::IDENTITY, |m, &(a, v)| rot(a, v) * m)
}

fn nums(fields: &[&str]) -> Vec<f64> {
    fields
        .iter()
        .map(|f| f.parse::<f64>().expect("number"))
        .collect()
}

struct RefBone {
    name: String,
    direction: DVec3,
    length: f64,
    /// C: the bone's axis frame.
    c: DMat3,
    dof: Vec<String>,
}

struct RefAsf {
    degrees: bool,
    root_order: Vec<String>,
    root_position: DVec3,
    root_c: DMat3,
    bones: Vec<RefBone>,
    parent: HashMap<String, String>,
}

fn parse_asf_ref(text: &str) -> RefAsf {
    let mut section = String::new();
    let mut asf = RefAsf {
        degrees: true,
        root_order: Vec::new(),
        root_position: DVec3::ZERO,
        root_c: DMat3::IDENTITY,
        bones: Vec::new(),
        parent: HashMap::new(),
    };
    let mut root_axis = "XYZ".to_string();
    let mut root_orientation = [0.0; 3];
    let mut bone: Option<(String, DVec3, f64, [f64; 3], String, Vec<String>)> = None;
    for line in text.lines() {
        let f: Vec<&str> = line.split_whitespace().collect();
        if f.is_empty() || f[0].starts_with('#') {
            continue;
        }
        if f[0].starts_with(':') {
            section = f[0].to_ascii_lowercase();
            continue;
        }
        let key = f[0].to_ascii_lowercase();
        match section.as_str() {
            ":units" if key == "angle" => asf.degrees = f[1].eq_ignore_ascii_case("deg"),
            ":root" => match key.as_str() {
                "order" => asf.root_order = f[1..].iter().map(|s| s.to_uppercase()).collect(),
                "axis" => root_axis = f[1].to_uppercase(),
                "position" => asf.root_position = DVec3::from_slice(&nums(&f[1..4])),
                "orientation" => root_orientation = nums(&f[1..4]).try_into().unwrap(),
                _ => {}
            },
            ":bonedata" => match key.as_str() {
                "begin" => {
                    bone = Some((
                        String::new(),
                        DVec3::ZERO,
                        0.0,
                        [0.0; 3],
                        "XYZ".into(),
                        vec![],
                    ))
                }
                "name" => bone.as_mut().unwrap().0 = f[1].to_string(),
                "direction" => bone.as_mut().unwrap().1 = DVec3::from_slice(&nums(&f[1..4])),
                "length" => bone.as_mut().unwrap().2 = nums(&f[1..2])[0],
                "axis" => {
                    let b = bone.as_mut().unwrap();
                    b.3 = nums(&f[1..4]).try_into().unwrap();
                    b.4 = f[4].to_uppercase();
                }
                "dof" => {
                    bone.as_mut().unwrap().5 = f[1..].iter().map(|s| s.to_lowercase()).collect()
                }
                "end" => {
                    let (name, direction, length, axis, order, dof) = bone.take().unwrap();
                    let c = euler_by_order(&order, axis, asf.degrees);
                    asf.bones.push(RefBone {
                        name,
                        direction,
                        length,
                        c,
                        dof,
                    });
                }
                _ => {}
            },
            ":hierarchy" => {
                if key == "begin" || key == "end" {
                    continue;
                }
                for child in &f[1..] {
                    asf.parent.insert(child.to_string(), f[0].to_string());
                }
            }
            _ => {}
        }
    }
    asf.root_c = euler_by_order(&root_axis, root_orientation, asf.degrees);
    asf
}

/// Angles given as (x, y, z), applied in the order the axis string lists.
fn euler_by_order(order: &str, xyz: [f64; 3], degrees: bool) -> DMat3 {
    let scale = if degrees {
        std::f64::consts::PI / 180.0
    } else {
        1.0
    };
    let list: Vec<(char, f64)> = order
        .chars()
        .map(|a| {
            let i = match a.to_ascii_lowercase() {
                'x' => 0,
                'y' => 1,
                _ => 2,
            };
            (a, xyz[i] * scale)
        })
        .collect();
    first_applied_first(&list)
}

/// AMC frames: per frame, bone name -> values.
fn parse_amc_ref(text: &str) -> Vec<HashMap<String, Vec<f64>>> {
    let mut frames: Vec<HashMap<String, Vec<f64>>> = Vec::new();
    for line in text.lines() {
        let f: Vec<&str> = line.split_whitespace().collect();
        if f.is_empty() || f[0].starts_with('#') || f[0].starts_with(':') {
            continue;
        }
        if f.len() == 1 && f[0].parse::<u64>().is_ok() {
            frames.push(HashMap::new());
            continue;
        }
        frames
            .last_mut()
            .expect("a frame number first")
            .insert(f[0].to_string(), nums(&f[1..]));
    }
    frames
}

/// World positions of every point the reference knows, by rigport's joint naming: `root`,
/// each bone's start under the bone's name, each bone's end under `<bone>_end`.
fn asf_fk(asf: &RefAsf, frame: &HashMap<String, Vec<f64>>) -> HashMap<String, DVec3> {
    let scale = if asf.degrees {
        std::f64::consts::PI / 180.0
    } else {
        1.0
    };
    let root_values = frame.get("root").cloned().unwrap_or_default();
    let mut t = DVec3::ZERO;
    let mut r = Vec::new();
    for (ch, v) in asf.root_order.iter().zip(&root_values) {
        let axis = ch.chars().nth(1).unwrap();
        match ch.chars().next().unwrap() {
            'T' => t[(axis as u8 - b'X') as usize] = *v,
            _ => r.push((axis, v * scale)),
        }
    }
    let root_w = asf.root_c * first_applied_first(&r) * asf.root_c.inverse();
    let root_pos = asf.root_position + t;
    let mut world: HashMap<String, (DMat3, DVec3)> = HashMap::new();
    world.insert("root".into(), (root_w, root_pos));
    let mut out = HashMap::new();
    out.insert("root".to_string(), root_pos);
    // Bones in hierarchy order: repeat until every bone whose parent is known is placed.
    let mut placed = 0;
    while placed < asf.bones.len() {
        let before = placed;
        for b in &asf.bones {
            if world.contains_key(&format!("{}#bone", b.name)) {
                continue;
            }
            let parent = &asf.parent[&b.name];
            let parent_end = if parent == "root" {
                Some((root_w, root_pos))
            } else {
                world.get(&format!("{parent}#bone")).map(|(w, _)| {
                    let (_, end) = world[&format!("{parent}#end")];
                    (*w, end)
                })
            };
            let Some((parent_w, start)) = parent_end else {
                continue;
            };
            let values = frame.get(&b.name).cloned().unwrap_or_default();
            let m: Vec<(char, f64)> = b
                .dof
                .iter()
                .zip(&values)
                .filter(|(d, _)| d.starts_with('r'))
                .map(|(d, v)| (d.chars().nth(1).unwrap(), v * scale))
                .collect();
            let w = parent_w * b.c * first_applied_first(&m) * b.c.inverse();
            let end = start + w * (b.direction * b.length);
            world.insert(format!("{}#bone", b.name), (w, start));
            world.insert(format!("{}#end", b.name), (w, end));
            out.insert(b.name.clone(), start);
            // rigport gives only leaf bones an end joint (a parent's end is where its
            // children start; checked through them).
            if !asf.parent.values().any(|p| p == &b.name) {
                out.insert(format!("{}_end", b.name), end);
            }
            placed += 1;
        }
        assert!(placed > before, "hierarchy does not reach every bone");
    }
    out
}

struct RefBvhJoint {
    name: String,
    parent: Option<usize>,
    offset: DVec3,
    channels: Vec<String>,
    first_channel: usize,
}

struct RefBvh {
    joints: Vec<RefBvhJoint>,
    frame_time: f64,
    frames: Vec<Vec<f64>>,
}

fn parse_bvh_ref(text: &str) -> RefBvh {
    let tokens: Vec<&str> = text.split_whitespace().collect();
    let mut joints: Vec<RefBvhJoint> = Vec::new();
    let mut stack: Vec<usize> = Vec::new();
    let mut channel_count = 0;
    let mut i = 0;
    let mut pending: Option<String> = None;
    while i < tokens.len() {
        let tok = tokens[i];
        match tok.to_ascii_uppercase().as_str() {
            "HIERARCHY" => i += 1,
            "ROOT" | "JOINT" => {
                pending = Some(tokens[i + 1].to_string());
                i += 2;
            }
            "END" => {
                let parent = *stack.last().unwrap();
                pending = Some(format!("{}_end", joints[parent].name));
                i += 2; // End Site
            }
            "{" => {
                joints.push(RefBvhJoint {
                    name: pending.take().unwrap(),
                    parent: stack.last().copied(),
                    offset: DVec3::ZERO,
                    channels: Vec::new(),
                    first_channel: channel_count,
                });
                stack.push(joints.len() - 1);
                i += 1;
            }
            "}" => {
                stack.pop();
                i += 1;
            }
            "OFFSET" => {
                let j = *stack.last().unwrap();
                joints[j].offset = DVec3::from_slice(&nums(&tokens[i + 1..i + 4]));
                i += 4;
            }
            "CHANNELS" => {
                let j = *stack.last().unwrap();
                let n: usize = tokens[i + 1].parse().unwrap();
                joints[j].channels = tokens[i + 2..i + 2 + n]
                    .iter()
                    .map(|s| s.to_string())
                    .collect();
                joints[j].first_channel = channel_count;
                channel_count += n;
                i += 2 + n;
            }
            "MOTION" => {
                i += 1;
                break;
            }
            other => panic!("unexpected token {other}"),
        }
    }
    // Frames: N  Frame Time: dt
    assert!(tokens[i].eq_ignore_ascii_case("Frames:"));
    let n: usize = tokens[i + 1].parse().unwrap();
    let frame_time: f64 = tokens[i + 4].parse().unwrap();
    let values = nums(&tokens[i + 5..]);
    let frames = values
        .chunks(channel_count)
        .take(n)
        .map(<[f64]>::to_vec)
        .collect();
    RefBvh {
        joints,
        frame_time,
        frames,
    }
}

/// World positions of every joint (End Sites as `<parent>_end`) at one frame.
fn bvh_fk(bvh: &RefBvh, frame: &[f64]) -> HashMap<String, DVec3> {
    let mut world: Vec<(DMat3, DVec3)> = Vec::with_capacity(bvh.joints.len());
    let mut out = HashMap::new();
    for j in &bvh.joints {
        let mut t = j.offset;
        let mut r = DMat3::IDENTITY;
        for (k, ch) in j.channels.iter().enumerate() {
            let v = frame[j.first_channel + k];
            let axis = ch.chars().next().unwrap().to_ascii_lowercase();
            if ch.to_ascii_lowercase().ends_with("position") {
                t[(axis as u8 - b'x') as usize] = v;
            } else {
                // Listed order multiplies left to right: R = R1 * R2 * R3.
                r *= rot(axis, v.to_radians());
            }
        }
        let (w, p) = match j.parent {
            Some(p) => {
                let (pw, pp) = world[p];
                (pw * r, pp + pw * t)
            }
            None => (r, t),
        };
        world.push((w, p));
        out.insert(j.name.clone(), p);
    }
    out
}

// ---------------------------------------------------------------------------------------
// Helpers over dumps and glTF files.

struct Frames {
    times: Vec<f64>,
    names: Vec<String>,
    /// Per frame, per joint: world position.
    positions: Vec<Vec<DVec3>>,
    /// Per frame, per joint: world rotation (from joint_world, in f64).
    rotations: Vec<Vec<DQuat>>,
}

fn eval_frames(args: &[&str], dir: &Path, tag: &str) -> Frames {
    let out = dir.join(format!("{tag}.npz"));
    let mut full: Vec<&str> = vec!["eval"];
    full.extend_from_slice(args);
    let out_s = out.to_str().unwrap().to_string();
    full.extend_from_slice(&["--out", &out_s, "--quiet"]);
    rigport_ok(&full);
    let npz = read_npz(&out);
    let jw = &npz["joint_world"];
    assert_eq!(jw.shape.len(), 4, "frame dump has F x J x 4 x 4");
    let (f, j) = (jw.shape[0], jw.shape[1]);
    let mut positions = Vec::with_capacity(f);
    let mut rotations = Vec::with_capacity(f);
    for fi in 0..f {
        let mut p = Vec::with_capacity(j);
        let mut r = Vec::with_capacity(j);
        for ji in 0..j {
            let m = &jw.numbers[(fi * j + ji) * 16..(fi * j + ji + 1) * 16];
            p.push(DVec3::new(m[3], m[7], m[11]));
            // Row-major storage: column c of the 3x3 is (m[c], m[4 + c], m[8 + c]).
            let cols: Vec<f64> = (0..9).map(|k| m[(k % 3) * 4 + k / 3]).collect();
            r.push(DQuat::from_mat3(&DMat3::from_cols_slice(&cols)).normalize());
        }
        positions.push(p);
        rotations.push(r);
    }
    Frames {
        times: npz["times"].numbers.clone(),
        names: npz["joint_names"].strings.clone(),
        positions,
        rotations,
    }
}

fn height(points: &[DVec3]) -> f64 {
    let lo = points.iter().fold(DVec3::splat(f64::MAX), |a, b| a.min(*b));
    let hi = points.iter().fold(DVec3::splat(f64::MIN), |a, b| a.max(*b));
    (hi - lo).max_element()
}

/// Samples a glTF channel at `t` (glTF 2.0 §3.11: LINEAR is lerp / slerp, STEP holds).
pub fn sample_channel(ch: &gltf_read::GltfChannel, t: f32) -> Vec<f32> {
    let n = ch.times.len();
    if t <= ch.times[0] || n == 1 {
        return ch.values[0].clone();
    }
    if t >= ch.times[n - 1] {
        return ch.values[n - 1].clone();
    }
    let k = ch.times.partition_point(|&x| x <= t) - 1;
    let (t0, t1) = (ch.times[k], ch.times[k + 1]);
    let u = (t - t0) / (t1 - t0);
    let (a, b) = (&ch.values[k], &ch.values[k + 1]);
    match ch.interpolation.as_str() {
        "Step" => a.clone(),
        "Linear" if ch.path == "Rotation" => {
            let qa = Quat::from_slice(a);
            let qb = Quat::from_slice(b);
            qa.slerp(qb, u).to_array().to_vec()
        }
        "Linear" => a.iter().zip(b).map(|(x, y)| x + (y - x) * u).collect(),
        other => panic!("interpolation {other} not expected in rigport's mocap output"),
    }
}

/// World positions of every node of `scene` with animation `a` applied at time `t`.
pub fn gltf_pose(scene: &GltfScene, a: usize, t: f32) -> Vec<Vec3> {
    let mut local = scene.local.clone();
    for ch in &scene.animations[a].channels {
        let v = sample_channel(ch, t);
        match ch.path.as_str() {
            "Translation" => local[ch.node].0 = Vec3::from_slice(&v),
            "Rotation" => local[ch.node].1 = Quat::from_slice(&v),
            "Scale" => local[ch.node].2 = Vec3::from_slice(&v),
            _ => {}
        }
    }
    let mut world: Vec<Option<Mat4>> = vec![None; local.len()];
    fn rec(
        i: usize,
        parents: &[Option<usize>],
        local: &[(Vec3, Quat, Vec3)],
        world: &mut Vec<Option<Mat4>>,
    ) -> Mat4 {
        if let Some(m) = world[i] {
            return m;
        }
        let (t, r, s) = local[i];
        let l = Mat4::from_scale_rotation_translation(s, r, t);
        let m = match parents[i] {
            Some(p) => rec(p, parents, local, world) * l,
            None => l,
        };
        world[i] = Some(m);
        m
    }
    (0..local.len())
        .map(|i| rec(i, &scene.parents, &local, &mut world).w_axis.truncate())
        .collect()
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Checks a converted mocap `.glb`: validator clean; frame count and rate; FK of the
/// glTF sampled with slerp at every frame equals the reference within 1e-5 of the height.
fn check_glb(
    glb: &Path,
    frames: usize,
    fps: f64,
    reference: &dyn Fn(usize) -> HashMap<String, DVec3>,
    tolerance: f64,
) {
    assert_valid(glb);
    let scene = gltf_read::read(glb);
    assert_eq!(
        scene.animations.len(),
        1,
        "{}: one animation",
        glb.display()
    );
    let anim = &scene.animations[0];
    let keys = anim.channels.iter().map(|c| c.times.len()).max().unwrap();
    assert_eq!(keys, frames, "{}: frame count", glb.display());
    let last = anim
        .channels
        .iter()
        .map(|c| *c.times.last().unwrap())
        .fold(0.0f32, f32::max) as f64;
    let expected_last = (frames - 1) as f64 / fps;
    assert!(
        (last - expected_last).abs() <= 1e-5 * expected_last.max(1.0),
        "{}: last key at {last} s, expected {expected_last} s ({frames} frames at {fps} fps)",
        glb.display()
    );
    let by_name = scene.node_by_name();
    let mut worst = 0.0f64;
    for f in 0..frames {
        let t = (f as f64 / fps) as f32;
        let world = gltf_pose(&scene, 0, t);
        let want = reference(f);
        for (name, p) in &want {
            let node = *by_name
                .get(name.as_str())
                .unwrap_or_else(|| panic!("{}: no node {name}", glb.display()));
            worst = worst.max((world[node].as_dvec3() - *p).length());
        }
    }
    assert!(
        worst <= tolerance,
        "{}: glTF sampled FK deviates {worst:e} from the reference (tolerance {tolerance:e})",
        glb.display()
    );
    eprintln!("{}: glTF FK max deviation {worst:.3e}", glb.display());
}

/// Checks eval frames against reference FK (every frame, every reference point), and
/// constant bone lengths. Returns the skeleton height.
fn check_eval(
    label: &str,
    dump: &Frames,
    reference: &dyn Fn(usize) -> HashMap<String, DVec3>,
    fps: f64,
) -> f64 {
    let index: HashMap<&str, usize> = dump
        .names
        .iter()
        .enumerate()
        .map(|(i, n)| (n.as_str(), i))
        .collect();
    let first = reference(0);
    let h = height(&first.values().copied().collect::<Vec<_>>());
    let tolerance = 1e-5 * h;
    let mut worst = 0.0f64;
    for (f, posed) in dump.positions.iter().enumerate() {
        assert!(
            (dump.times[f] - f as f64 / fps).abs() < 1e-4 / fps.max(1.0) + 1e-6,
            "{label}: frame {f} at {} s",
            dump.times[f]
        );
        let want = reference(f);
        for (name, p) in &want {
            let j = *index
                .get(name.as_str())
                .unwrap_or_else(|| panic!("{label}: rigport has no joint {name}"));
            let d = (posed[j] - *p).length();
            worst = worst.max(d);
            assert!(
                d <= tolerance,
                "{label}: frame {f} joint {name}: rigport {:?} vs reference {p:?} ({d:e} > {tolerance:e})",
                posed[j]
            );
        }
    }
    eprintln!(
        "{label}: eval FK max deviation {worst:.3e} (tolerance {tolerance:.3e}, height {h:.3})"
    );
    h
}

/// Bone lengths (joint to parent distance) of rigport's dump stay constant over frames,
/// except for joints driven by position channels (`moving`).
fn check_bone_lengths(label: &str, dump: &Frames, parents: &HashMap<String, String>, h: f64) {
    let index: HashMap<&str, usize> = dump
        .names
        .iter()
        .enumerate()
        .map(|(i, n)| (n.as_str(), i))
        .collect();
    for (child, parent) in parents {
        let (Some(&c), Some(&p)) = (index.get(child.as_str()), index.get(parent.as_str())) else {
            continue;
        };
        let rest = (dump.positions[0][c] - dump.positions[0][p]).length();
        for (f, frame) in dump.positions.iter().enumerate() {
            let len = (frame[c] - frame[p]).length();
            assert!(
                (len - rest).abs() <= 1e-5 * h,
                "{label}: bone {parent}->{child} length {len} at frame {f}, {rest} at frame 0"
            );
        }
    }
}

// ---------------------------------------------------------------------------------------
// Acceptance 1-3 on the corpus.

#[test]
fn asf_amc_corpus_converts_and_matches_reference_fk() {
    for (asf_rel, amc_rel) in ASF_AMC {
        let (Some(asf), Some(amc)) = (corpus(asf_rel), corpus(amc_rel)) else {
            return;
        };
        let label = amc.file_name().unwrap().to_string_lossy().into_owned();
        let dir = scratch();
        let reference_asf = parse_asf_ref(&std::fs::read_to_string(&asf).unwrap());
        let frames = parse_amc_ref(&std::fs::read_to_string(&amc).unwrap());
        let reference = |f: usize| asf_fk(&reference_asf, &frames[f]);
        let fps = 120.0;

        let dump = eval_frames(&[s(&asf), "--motion", s(&amc)], dir.path(), "eval");
        assert_eq!(dump.positions.len(), frames.len(), "{label}: frame count");
        let h = check_eval(&label, &dump, &reference, fps);
        let mut parents: HashMap<String, String> = reference_asf
            .parent
            .iter()
            .map(|(c, p)| (c.clone(), p.clone()))
            .collect();
        for b in &reference_asf.bones {
            parents.insert(format!("{}_end", b.name), b.name.clone());
        }
        parents.retain(|_, p| p != "root");
        check_bone_lengths(&label, &dump, &parents, h);

        let glb = dir.path().join("out.glb");
        rigport_ok(&[
            "convert",
            s(&asf),
            "--motion",
            s(&amc),
            "-o",
            s(&glb),
            "--quiet",
        ]);
        // glTF is in metres: the ASF's `:units length` (inches per unit) converts it.
        let mpu = asf_meters_per_unit(&std::fs::read_to_string(&asf).unwrap());
        let in_metres = |f: usize| {
            let mut r = reference(f);
            r.values_mut().for_each(|p| *p *= mpu);
            r
        };
        check_glb(&glb, frames.len(), fps, &in_metres, 1e-5 * h * mpu);
    }
}

/// Metres per unit of an ASF: `0.0254 / length` when `:units` states `length`, else 1.
fn asf_meters_per_unit(text: &str) -> f64 {
    let mut in_units = false;
    for line in text.lines().map(str::trim) {
        if line.starts_with(':') {
            in_units = line.starts_with(":units");
            continue;
        }
        if let (true, Some(v)) = (in_units, line.strip_prefix("length")) {
            return 0.0254 / v.trim().parse::<f64>().unwrap();
        }
    }
    1.0
}

#[test]
fn bvh_corpus_converts_and_matches_reference_fk() {
    for rel in BVH {
        let Some(path) = corpus(rel) else {
            return;
        };
        let label = path.file_name().unwrap().to_string_lossy().into_owned();
        let dir = scratch();
        let bvh = parse_bvh_ref(&std::fs::read_to_string(&path).unwrap());
        let reference = |f: usize| bvh_fk(&bvh, &bvh.frames[f]);
        let fps = 1.0 / bvh.frame_time;

        let dump = eval_frames(&[s(&path)], dir.path(), "eval");
        assert_eq!(
            dump.positions.len(),
            bvh.frames.len(),
            "{label}: frame count"
        );
        let h = check_eval(&label, &dump, &reference, fps);
        // Joints with position channels may change length; the others may not.
        let parents: HashMap<String, String> = bvh
            .joints
            .iter()
            .filter(|j| {
                !j.channels
                    .iter()
                    .any(|c| c.to_ascii_lowercase().ends_with("position"))
            })
            .filter_map(|j| {
                j.parent
                    .map(|p| (j.name.clone(), bvh.joints[p].name.clone()))
            })
            .collect();
        check_bone_lengths(&label, &dump, &parents, h);

        let glb = dir.path().join("out.glb");
        rigport_ok(&["convert", s(&path), "-o", s(&glb), "--quiet"]);
        check_glb(&glb, bvh.frames.len(), fps, &reference, 1e-5 * h);
    }
}

#[test]
fn several_amc_files_become_several_clips_and_fps_is_honoured() {
    let (Some(asf), Some(walk), Some(run)) = (
        corpus(ASF_AMC[0].0),
        corpus(ASF_AMC[0].1),
        corpus(ASF_AMC[1].1),
    ) else {
        return;
    };
    let dir = scratch();
    let glb = dir.path().join("two.glb");
    // 09_06-run was captured on subject 09; CMU skeletons share bone names, so it plays on 07.
    rigport_ok(&[
        "convert",
        s(&asf),
        "--motion",
        s(&walk),
        "--motion",
        s(&run),
        "--fps",
        "60",
        "-o",
        s(&glb),
        "--quiet",
    ]);
    assert_valid(&glb);
    let scene = gltf_read::read(&glb);
    let names: Vec<&str> = scene.animations.iter().map(|a| a.name.as_str()).collect();
    assert_eq!(names, ["07_05-walk", "09_06-run"]);
    let frames = parse_amc_ref(&std::fs::read_to_string(&walk).unwrap()).len();
    let last = scene.animations[0]
        .channels
        .iter()
        .map(|c| *c.times.last().unwrap())
        .fold(0.0f32, f32::max);
    assert!(((last as f64) - (frames - 1) as f64 / 60.0).abs() < 1e-4);
}

#[test]
fn skeleton_only_inputs_get_a_bone_mesh_unless_told_not_to() {
    let Some(bvh) = corpus(BVH[3]) else {
        return;
    };
    let dir = scratch();
    let with = dir.path().join("with.glb");
    let without = dir.path().join("without.glb");
    rigport_ok(&["convert", s(&bvh), "-o", s(&with), "--quiet"]);
    rigport_ok(&[
        "convert",
        s(&bvh),
        "--no-bone-mesh",
        "-o",
        s(&without),
        "--quiet",
    ]);
    assert_valid(&with);
    assert_valid(&without);
    let a = gltf_read::read(&with);
    let b = gltf_read::read(&without);
    assert_eq!(a.skins.len(), 1, "the bone mesh is skinned");
    assert!(a.skins[0].positions.len() > 100);
    assert!(b.skins.is_empty());
    // The bone mesh follows the motion: skinned by the test reader at the last frame, its
    // vertices stay close to the joints they are bound to.
    let anim = &a.animations[0];
    let t = anim
        .channels
        .iter()
        .map(|c| *c.times.last().unwrap())
        .fold(0.0f32, f32::max);
    let mut local = a.local.clone();
    for ch in &anim.channels {
        let v = sample_channel(ch, t);
        match ch.path.as_str() {
            "Translation" => local[ch.node].0 = Vec3::from_slice(&v),
            "Rotation" => local[ch.node].1 = Quat::from_slice(&v),
            _ => {}
        }
    }
    let posed = GltfScene {
        node_names: a.node_names.clone(),
        parents: a.parents.clone(),
        local,
        skins: Vec::new(),
        animations: Vec::new(),
    };
    let world = posed.world(&HashMap::new());
    let skinned = a.skin_positions(0, &world);
    let rest_world = a.world(&HashMap::new());
    let joints: Vec<Vec3> = world.iter().map(|m| m.w_axis.truncate()).collect();
    let rest_joints: Vec<Vec3> = rest_world.iter().map(|m| m.w_axis.truncate()).collect();
    let h = height(&rest_joints.iter().map(|p| p.as_dvec3()).collect::<Vec<_>>()) as f32;
    for (v, infl) in a.skins[0].influences.iter().enumerate() {
        let (node, _) = infl[0];
        let rest_d = (a.skins[0].positions[v] - rest_joints[node]).length();
        let posed_d = (skinned[v] - joints[node]).length();
        assert!(
            (rest_d - posed_d).abs() < 1e-3 * h,
            "vertex {v} moved off its bone"
        );
    }
}

// ---------------------------------------------------------------------------------------
// Acceptance 4: time warping through the CLI.

/// The largest rotation angle between the joints' world rotations of two frames, in
/// radians. From the chord between the quaternions (acos near 1 would lose the precision).
fn max_angle(a: &Frames, b: &Frames, fa: usize, fb: usize) -> f64 {
    a.rotations[fa]
        .iter()
        .zip(&b.rotations[fb])
        .map(|(x, y)| {
            let chord = (*x - *y).length().min((*x + *y).length());
            4.0 * (chord / 2.0).min(1.0).asin()
        })
        .fold(0.0, f64::max)
}

#[test]
fn retime_identity_round_trip_speed_reverse_and_bad_warp() {
    let Some(bvh) = corpus(BVH[3]) else {
        return;
    };
    let dir = scratch();
    let p = |n: &str| dir.path().join(n);
    let src = eval_frames(&[s(&bvh)], dir.path(), "src");
    let n = src.times.len();
    let n_s = n.to_string();
    let n2_s = (2 * n - 1).to_string();

    // Same frame count: identity.
    rigport_ok(&[
        "retime",
        s(&bvh),
        "--frames",
        &n_s,
        "-o",
        s(&p("same.glb")),
        "--quiet",
    ]);
    assert_valid(&p("same.glb"));
    let same = eval_frames(&[s(&p("same.glb"))], dir.path(), "same");
    assert_eq!(same.times.len(), n);
    for f in 0..n {
        assert!(max_angle(&src, &same, f, f) < 1e-4, "frame {f} changed");
    }

    // Twice the frames and back: within 1e-4 rad per joint.
    rigport_ok(&[
        "retime",
        s(&bvh),
        "--frames",
        &n2_s,
        "-o",
        s(&p("double.glb")),
        "--quiet",
    ]);
    rigport_ok(&[
        "retime",
        s(&p("double.glb")),
        "--frames",
        &n_s,
        "-o",
        s(&p("back.glb")),
        "--quiet",
    ]);
    let back = eval_frames(&[s(&p("back.glb"))], dir.path(), "back");
    let worst = (0..n)
        .map(|f| max_angle(&src, &back, f, f))
        .fold(0.0, f64::max);
    assert!(worst <= 1e-4, "2x and back: {worst} rad");

    // Speed 0.5 doubles the duration.
    rigport_ok(&[
        "retime",
        s(&bvh),
        "--speed",
        "0.5",
        "-o",
        s(&p("slow.glb")),
        "--quiet",
    ]);
    let slow = eval_frames(&[s(&p("slow.glb"))], dir.path(), "slow");
    let d0 = src.times[n - 1] - src.times[0];
    let d1 = slow.times.last().unwrap() - slow.times[0];
    assert!((d1 - 2.0 * d0).abs() < 1e-4, "duration {d0} -> {d1}");

    // Reverse: the first frame of the result is the source's last.
    rigport_ok(&[
        "retime",
        s(&bvh),
        "--reverse",
        "-o",
        s(&p("rev.glb")),
        "--quiet",
    ]);
    let rev = eval_frames(&[s(&p("rev.glb"))], dir.path(), "rev");
    assert!(max_angle(&src, &rev, n - 1, 0) < 1e-4);
    assert!(max_angle(&src, &rev, 0, rev.times.len() - 1) < 1e-4);

    // Quaternion outputs are sign-continuous in the files.
    for file in ["double.glb", "slow.glb", "rev.glb"] {
        let scene = gltf_read::read(&p(file));
        for ch in scene.animations[0]
            .channels
            .iter()
            .filter(|c| c.path == "Rotation")
        {
            for w in ch.values.windows(2) {
                let d: f32 = w[0].iter().zip(&w[1]).map(|(a, b)| a * b).sum();
                assert!(d >= 0.0, "{file}: sign flip between keys");
            }
        }
    }

    // A non-monotone warp curve is rejected, naming the key, and nothing is written.
    let out = rigport(&[
        "retime",
        s(&bvh),
        "--warp",
        "0:0,1:0.8,2:0.4",
        "-o",
        s(&p("warp.glb")),
    ]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("0.4") && err.contains("warp"), "{err}");
    assert!(!p("warp.glb").exists());
    // A monotone one works and validates.
    rigport_ok(&[
        "retime",
        s(&bvh),
        "--warp",
        "0:0,1:0.4,2:2",
        "-o",
        s(&p("warp.glb")),
        "--quiet",
    ]);
    assert_valid(&p("warp.glb"));
}

// ---------------------------------------------------------------------------------------
// Acceptance 5: keyframes on a Pinocchio rig.

#[test]
fn animate_three_keys_matches_eval_pose_at_each_key() {
    let Some((_, mesh, skel, att)) = PINOCCHIO_RIGS
        .iter()
        .find(|r| r.0 == "model1")
        .and_then(|r| Some((r.0, corpus(r.1)?, corpus(r.2)?, corpus(r.3)?)))
    else {
        return;
    };
    let dir = scratch();
    let p = |n: &str| dir.path().join(n);
    let poses = [
        r#"{}"#,
        r#"{"bone_3": {"euler_deg": [0, 30, 45], "order": "zxy"}, "bone_7": {"quat": [0.2, 0, 0, 0.98]}}"#,
        r#"{"bone_3": {"euler_deg": [10, -20, 5]}, "bone_12": {"euler_deg": [0, 0, 60], "order": "yxz"}}"#,
    ];
    let times = [0.0, 0.4, 1.25];
    let keys: Vec<String> = poses
        .iter()
        .zip(times)
        .map(|(pose, t)| format!(r#"{{"time": {t}, "pose": {pose}}}"#))
        .collect();
    std::fs::write(
        p("keys.json"),
        format!(r#"{{"name": "three", "keys": [{}]}}"#, keys.join(",")),
    )
    .unwrap();
    let glb = p("animated.glb");
    rigport_ok(&[
        "animate",
        s(&mesh),
        s(&skel),
        s(&att),
        "--keys",
        s(&p("keys.json")),
        "-o",
        s(&glb),
        "--quiet",
    ]);
    assert_valid(&glb);
    let clip = eval_frames(&[s(&glb)], dir.path(), "clip");
    assert_eq!(clip.times.len(), 3);
    let clip_npz = read_npz(&dir.path().join("clip.npz"));
    let v3 = clip_npz["rest_positions"].shape[0] * 3;
    for (k, pose) in poses.iter().enumerate() {
        assert!((clip.times[k] - times[k]).abs() < 1e-6);
        let pose_path = p(&format!("pose{k}.json"));
        std::fs::write(&pose_path, pose).unwrap();
        // Same rig from the original files, posed directly.
        let out = p(&format!("pose{k}.npz"));
        rigport_ok(&[
            "eval",
            s(&mesh),
            s(&skel),
            s(&att),
            "--pose",
            s(&pose_path),
            "--out",
            s(&out),
            "--quiet",
        ]);
        let direct = read_npz(&out);
        let names = &direct["joint_names"].strings;
        let jw = &direct["joint_world"].numbers;
        for (j, name) in names.iter().enumerate() {
            let c = clip.names.iter().position(|n| n == name).unwrap();
            let want = DVec3::new(jw[j * 16 + 3], jw[j * 16 + 7], jw[j * 16 + 11]);
            let d = (clip.positions[k][c] - want).length();
            assert!(
                d <= 1e-6 * want.length().max(1.0),
                "key {k} joint {name}: {d:e}"
            );
        }
        // The glTF's own pose at the key equals its clip frame, vertex by vertex.
        let out_glb = p(&format!("pose{k}_glb.npz"));
        rigport_ok(&[
            "eval",
            s(&glb),
            "--pose",
            s(&pose_path),
            "--out",
            s(&out_glb),
            "--quiet",
        ]);
        let posed = &read_npz(&out_glb)["positions"].numbers;
        let framed = &clip_npz["positions"].numbers[k * v3..(k + 1) * v3];
        let worst = posed
            .iter()
            .zip(framed)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(
            worst <= 1e-6,
            "key {k}: clip frame vs eval --pose: {worst:e}"
        );
    }
}

#[test]
fn bad_motion_inputs_fail_cleanly() {
    let dir = scratch();
    let p = |n: &str| dir.path().join(n);
    let asf = repo().join("fixtures/asf_amc");
    let bvh_dir = repo().join("fixtures/bvh");
    let first = |d: &PathBuf, ext: &str| -> Option<PathBuf> {
        let mut v: Vec<PathBuf> = std::fs::read_dir(d)
            .ok()?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|e| e == ext))
            .collect();
        v.sort();
        v.into_iter().next()
    };
    // A BVH cut inside its hierarchy.
    let bvh = first(&bvh_dir, "bvh").expect("fixtures/bvh has a .bvh");
    let text = std::fs::read_to_string(&bvh).unwrap();
    let cut = &text[..text.find("MOTION").unwrap() / 2];
    std::fs::write(p("cut.bvh"), cut).unwrap();
    let out = rigport(&["convert", s(&p("cut.bvh")), "-o", s(&p("cut.glb"))]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("cut.bvh:"), "{err}");
    assert!(!p("cut.glb").exists());
    // An AMC naming a bone the skeleton lacks.
    let asf_file = first(&asf, "asf").expect("fixtures/asf_amc has an .asf");
    std::fs::write(
        p("bad.amc"),
        ":FULLY-SPECIFIED\n:DEGREES\n1\nroot 0 0 0 0 0 0\nnosuchbone 1 2 3\n",
    )
    .unwrap();
    let out = rigport(&[
        "convert",
        s(&asf_file),
        "--motion",
        s(&p("bad.amc")),
        "-o",
        s(&p("bad.glb")),
    ]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("bad.amc:5"), "{err}");
    assert!(!p("bad.glb").exists());
    // --fps without an ASF is a usage mistake with a clear message.
    let out = rigport(&["convert", s(&bvh), "--fps", "30", "-o", s(&p("x.glb"))]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("retime"));
}
