//! Tests of the character: determinism, skeleton, a closed clean mesh, weights that keep
//! to their limbs.

use super::*;
use crate::weights::MAX_INFLUENCES;
use rigport_model::Mesh;
use std::sync::OnceLock;

/// The rigs of detail 1 and 2, built once for all tests (debug builds are slow).
fn built(detail: u32) -> &'static DemoRig {
    static RIGS: [OnceLock<DemoRig>; 2] = [OnceLock::new(), OnceLock::new()];
    RIGS[detail as usize - 1].get_or_init(|| character(detail))
}

fn signed_volume(mesh: &Mesh) -> f32 {
    let p = |i: u32| mesh.positions[i as usize].as_dvec3();
    let v: f64 = mesh
        .triangles
        .iter()
        .map(|&[a, b, c]| p(a).dot(p(b).cross(p(c))) / 6.0)
        .sum();
    v as f32
}

fn joint(rig: &DemoRig, name: &str) -> usize {
    rig.joint_names.iter().position(|n| n == name).unwrap()
}

#[test]
fn is_deterministic() {
    assert_eq!(&character(1), built(1));
    assert_eq!(&character(0), built(1), "detail 0 means 1");
}

#[test]
fn skeleton_is_a_pinocchio_humanoid() {
    let rig = built(1);
    let n = rig.joint_names.len();
    assert_eq!(n, 24);
    assert_eq!(rig.joint_positions.len(), n);
    assert_eq!(rig.joint_parents.len(), n);
    assert_eq!(rig.joint_parents[0], None);
    for (j, p) in rig.joint_parents.iter().enumerate().skip(1) {
        assert!(p.is_some_and(|p| p < j), "joint {j} parent {p:?}");
    }
    let mut names = rig.joint_names.clone();
    names.sort();
    names.dedup();
    assert_eq!(names.len(), n, "unique names");
    let chain = |first: &str, side: &str, rest: &[&str]| {
        let mut names = vec![first.to_owned()];
        names.extend(rest.iter().map(|n| format!("{n}{side}")));
        for w in names.windows(2) {
            assert_eq!(
                rig.joint_parents[joint(rig, &w[1])],
                Some(joint(rig, &w[0]))
            );
        }
    };
    chain("hips", "", &["spine", "chest", "neck", "head", "head_top"]);
    for side in ["_l", "_r"] {
        let arm = ["shoulder", "upper_arm", "forearm", "hand", "fingertip"];
        chain("chest", side, &arm);
        chain("hips", side, &["thigh", "shin", "foot", "toe"]);
    }
    // Left is +X, mirrored exactly.
    let (l, r) = (joint(rig, "hand_l"), joint(rig, "hand_r"));
    assert!(rig.joint_positions[l].x > 0.5);
    assert_eq!(
        rig.joint_positions[r],
        rig.joint_positions[l] * Vec3::new(-1.0, 1.0, 1.0)
    );
    // The toes point forward (+Z).
    assert!(rig.joint_positions[joint(rig, "toe_l")].z > 0.1);
}

#[test]
fn mesh_size_and_shape() {
    let rig = built(1);
    let mesh = &rig.mesh;
    let v = mesh.vertex_count();
    assert!((5_000..=15_000).contains(&v), "{v} vertices");
    assert_eq!(mesh.name, "demo");
    assert_eq!(mesh.source_vertex, (0..v as u32).collect::<Vec<_>>());
    assert_eq!(mesh.normals.as_ref().map(Vec::len), Some(v));
    let (lo, hi) = mesh.bounds().unwrap();
    assert!((hi.y - lo.y - 1.75).abs() < 0.1, "height {}", hi.y - lo.y);
    assert!(lo.y.abs() < 0.01, "feet at y = {}", lo.y);
    assert!(hi.x > 0.8 && lo.x < -0.8, "arms along x: {lo} {hi}");
    // The finer grid makes the same body.
    let fine = built(2);
    assert!(fine.mesh.vertex_count() > 3 * v);
    let (flo, fhi) = fine.mesh.bounds().unwrap();
    assert!((flo - lo).abs().max_element() < 0.01 && (fhi - hi).abs().max_element() < 0.01);
}

#[test]
fn mesh_is_closed_outward_and_clean() {
    for detail in [1, 2] {
        let mesh = &built(detail).mesh;
        // Closed and consistently wound: every directed edge once, and its reverse once.
        let mut edges: Vec<(u32, u32)> = mesh
            .triangles
            .iter()
            .flat_map(|&[a, b, c]| [(a, b), (b, c), (c, a)])
            .collect();
        edges.sort_unstable();
        let n = edges.len();
        edges.dedup();
        assert_eq!(
            edges.len(),
            n,
            "detail {detail}: a directed edge is used twice"
        );
        for &(a, b) in &edges {
            assert!(edges.binary_search(&(b, a)).is_ok(), "open edge {a}-{b}");
        }
        assert!(signed_volume(mesh) > 0.03, "volume {}", signed_volume(mesh));
        // Every vertex used, no zero-area triangle, normals agree with the winding.
        let mut used = vec![false; mesh.vertex_count()];
        let normals = mesh.normals.as_ref().unwrap();
        let mut disagree = 0;
        for &[a, b, c] in &mesh.triangles {
            let p = |i: u32| mesh.positions[i as usize];
            let n = (p(b) - p(a)).cross(p(c) - p(a));
            assert!(n.length() > 1e-10, "degenerate triangle {a} {b} {c}");
            for v in [a, b, c] {
                used[v as usize] = true;
                if n.dot(normals[v as usize]) < 0.0 {
                    disagree += 1;
                }
            }
        }
        assert!(used.iter().all(|u| *u));
        assert!(
            disagree * 1000 < mesh.triangles.len(),
            "{disagree} flipped corners"
        );
    }
}

#[test]
fn weight_rows_are_normalized() {
    let rig = built(1);
    assert_eq!(rig.bone_weights.len(), rig.mesh.vertex_count());
    for row in &rig.bone_weights {
        assert_eq!(row.len(), rig.joint_names.len() - 1);
        assert!(row.iter().all(|w| w.is_finite() && *w >= 0.0), "{row:?}");
        assert!(row.iter().filter(|w| **w > 0.0).count() <= MAX_INFLUENCES);
        let sum: f32 = row.iter().sum();
        assert!((sum - 1.0).abs() <= 1e-6, "sum {sum}");
    }
}

#[test]
fn hands_belong_to_their_arm() {
    let rig = built(1);
    for s in ["l", "r"] {
        let hand = rig.joint_positions[joint(rig, &format!("hand_{s}"))];
        let nearest = (0..rig.mesh.vertex_count())
            .min_by(|&a, &b| {
                let d = |v: usize| rig.mesh.positions[v].distance_squared(hand);
                d(a).total_cmp(&d(b))
            })
            .unwrap();
        let row = &rig.bone_weights[nearest];
        let best = (0..row.len())
            .max_by(|&a, &b| row[a].total_cmp(&row[b]))
            .unwrap();
        // Column k - 1 is the bone ending at joint k: forearm_s -> hand_s, hand_s -> tip.
        let wrist_bones = [
            joint(rig, &format!("hand_{s}")),
            joint(rig, &format!("fingertip_{s}")),
        ];
        assert!(
            wrist_bones.contains(&(best + 1)),
            "{s}: best bone {}",
            best + 1
        );
        // Every vertex beyond the elbow is weighted to that arm only.
        let elbow = rig.joint_positions[joint(rig, &format!("forearm_{s}"))];
        let arm: Vec<usize> = ["upper_arm", "forearm", "hand", "fingertip"]
            .iter()
            .map(|n| joint(rig, &format!("{n}_{s}")) - 1)
            .collect();
        for (p, row) in rig.mesh.positions.iter().zip(&rig.bone_weights) {
            if p.x.abs() > elbow.x.abs() + 0.05 && p.x * elbow.x > 0.0 {
                let on_arm: f32 = arm.iter().map(|&b| row[b]).sum();
                assert!(on_arm > 0.999, "{s} {p}: {row:?}");
            }
        }
    }
}

#[test]
fn head_has_no_leg_or_arm_weight() {
    let rig = built(1);
    let neck = rig.joint_positions[joint(rig, "head")];
    let foreign: Vec<usize> = (1..rig.joint_names.len())
        .filter(|&j| {
            [
                "thigh",
                "shin",
                "foot",
                "toe",
                "forearm",
                "hand",
                "fingertip",
            ]
            .iter()
            .any(|n| rig.joint_names[j].starts_with(n))
        })
        .map(|j| j - 1)
        .collect();
    let mut head_vertices = 0;
    for (p, row) in rig.mesh.positions.iter().zip(&rig.bone_weights) {
        if p.y > neck.y {
            head_vertices += 1;
            assert!(foreign.iter().all(|&b| row[b] == 0.0), "{p}: {row:?}");
        }
    }
    assert!(head_vertices > 300);
}

#[test]
fn legs_keep_to_themselves() {
    // Below the crotch (at 0.80 m) no vertex of one leg moves with the other leg.
    let rig = built(1);
    for (side, other) in [(1.0, "_r"), (-1.0, "_l")] {
        let bones: Vec<usize> = ["thigh", "shin", "foot", "toe"]
            .iter()
            .map(|n| joint(rig, &format!("{n}{other}")) - 1)
            .collect();
        for (p, row) in rig.mesh.positions.iter().zip(&rig.bone_weights) {
            if p.y < 0.75 && p.x * side > 0.0 {
                assert!(bones.iter().all(|&b| row[b] == 0.0), "{p}: {row:?}");
            }
        }
    }
}

#[test]
fn weights_are_smooth_over_edges() {
    // Continuous weights: the largest change across a mesh edge is bounded and shrinks
    // as the edges do. The largest steps sit in the tightest creases (front of the
    // ankle, the crotch, where the two legs part); measured 0.56 and 0.42.
    for (detail, limit) in [(1, 0.6), (2, 0.45)] {
        let rig = built(detail);
        let mut jumps = Vec::new();
        for t in &rig.mesh.triangles {
            for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                let (ra, rb) = (&rig.bone_weights[a as usize], &rig.bone_weights[b as usize]);
                let diff = ra.iter().zip(rb).map(|(x, y)| (x - y).abs());
                jumps.push(diff.fold(0.0, f32::max));
            }
        }
        let worst = jumps.iter().copied().fold(0.0, f32::max);
        assert!(
            worst < limit,
            "detail {detail}: weight jump {worst} across an edge"
        );
        let large = jumps.iter().filter(|j| **j > 0.3).count();
        assert!(
            large * 50 < jumps.len(),
            "detail {detail}: {large} jumps over 0.3"
        );
    }
}

/// Writes `rigport_demo.obj` and orthographic views `rigport_demo_*.pgm` (front and side
/// shaded by normal; front with one bone's weights as brightness) to the temp directory
/// (`/tmp`), to look at: `cargo test -p rigport-import --release -- --ignored dump_for`.
#[test]
#[ignore = "writes files to the temp directory for a visual check"]
fn dump_for_visual_check() {
    use std::fmt::Write as _;
    let rig = built(1);
    let mesh = &rig.mesh;
    let dir = std::env::temp_dir();
    let mut obj = String::new();
    for p in &mesh.positions {
        writeln!(obj, "v {} {} {}", p.x, p.y, p.z).unwrap();
    }
    for n in mesh.normals.as_ref().unwrap() {
        writeln!(obj, "vn {} {} {}", n.x, n.y, n.z).unwrap();
    }
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| i + 1);
        writeln!(obj, "f {a}//{a} {b}//{b} {c}//{c}").unwrap();
    }
    std::fs::write(dir.join("rigport_demo.obj"), obj).unwrap();
    // Orthographic z-buffered rasterizer: front (+Z towards the viewer) or side (from
    // -X, the character's right).
    let render = |name: &str, side: bool, shade: &dyn Fn(usize, Vec3) -> f32| {
        let (w, h, scale) = (400usize, 400usize, 400.0 / 2.0);
        let mut img = vec![0u8; w * h];
        let mut depth = vec![f32::MIN; w * h];
        let project = |p: Vec3| {
            let (u, d) = if side { (p.z, -p.x) } else { (p.x, p.z) };
            (u * scale + w as f32 / 2.0, (1.9 - p.y) * scale, d)
        };
        for t in &mesh.triangles {
            let [a, b, c] = t.map(|i| project(mesh.positions[i as usize]));
            let area = (b.0 - a.0) * (c.1 - a.1) - (c.0 - a.0) * (b.1 - a.1);
            if area.abs() < 1e-9 {
                continue;
            }
            let x0 = a.0.min(b.0).min(c.0).floor().max(0.0) as usize;
            let x1 = (a.0.max(b.0).max(c.0).ceil() as usize).min(w - 1);
            let y0 = a.1.min(b.1).min(c.1).floor().max(0.0) as usize;
            let y1 = (a.1.max(b.1).max(c.1).ceil() as usize).min(h - 1);
            for y in y0..=y1 {
                for x in x0..=x1 {
                    let (px, py) = (x as f32 + 0.5, y as f32 + 0.5);
                    let l1 = ((b.0 - px) * (c.1 - py) - (c.0 - px) * (b.1 - py)) / area;
                    let l2 = ((c.0 - px) * (a.1 - py) - (a.0 - px) * (c.1 - py)) / area;
                    let l3 = 1.0 - l1 - l2;
                    if l1 < 0.0 || l2 < 0.0 || l3 < 0.0 {
                        continue;
                    }
                    let d = l1 * a.2 + l2 * b.2 + l3 * c.2;
                    if d > depth[x + w * y] {
                        depth[x + w * y] = d;
                        let verts = t.map(|i| i as usize);
                        let k = [l1, l2, l3]
                            .iter()
                            .enumerate()
                            .max_by(|p, q| p.1.total_cmp(q.1))
                            .unwrap()
                            .0;
                        let n = mesh.normals.as_ref().unwrap();
                        let nn = n[verts[0]] * l1 + n[verts[1]] * l2 + n[verts[2]] * l3;
                        let v = shade(verts[k], nn.normalize());
                        img[x + w * y] = (v.clamp(0.0, 1.0) * 255.0) as u8;
                    }
                }
            }
        }
        let mut out = format!("P5 {w} {h} 255\n").into_bytes();
        out.extend(img);
        std::fs::write(dir.join(format!("rigport_demo_{name}.pgm")), out).unwrap();
    };
    let light = Vec3::new(0.4, 0.5, 1.0).normalize();
    let light_side = Vec3::new(-1.0, 0.5, 0.4).normalize();
    render("front", false, &|_, n| 0.15 + 0.85 * n.dot(light).max(0.0));
    render("side", true, &|_, n| {
        0.15 + 0.85 * n.dot(light_side).max(0.0)
    });
    for name in [
        "forearm_l",
        "shin_l",
        "spine",
        "neck",
        "thigh_l",
        "upper_arm_l",
    ] {
        let b = joint(rig, name) - 1;
        render(&format!("w_{name}"), false, &|v, n| {
            0.1 + 0.2 * n.dot(light).max(0.0) + 0.7 * rig.bone_weights[v][b]
        });
    }
}
