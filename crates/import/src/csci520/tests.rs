use glam::{DMat4, Mat4, Vec3};
use rigport_model::{parents_first_order, Asset, Influence, Influences, Skeleton};

use super::*;

const FIXTURES: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/csci520");
const CORPUS: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../../shared/corpus/2_csci520_ik_skinning"
);

/// Model-space rest matrices evaluated in `f64` from the stored `f32` rest transforms.
fn model_f64(skeleton: &Skeleton) -> Vec<DMat4> {
    let mut out: Vec<DMat4> = Vec::with_capacity(skeleton.len());
    for joint in skeleton.joints() {
        let t = &joint.rest_local;
        let local = DMat4::from_scale_rotation_translation(
            t.scale.as_dvec3(),
            t.rotation.as_dquat(),
            t.translation.as_dvec3(),
        );
        let m = match joint.parent {
            Some(p) => out[p.get()] * local,
            None => local,
        };
        out.push(m);
    }
    out
}

/// (largest |skin matrix - identity| entry, largest |LBS(p) - p| coordinate), skin
/// matrix = model rest (f64 from the stored transforms) · inverse bind, LBS in f64.
fn bind_pose_errors(asset: &Asset) -> (f64, f64) {
    let skin = &asset.skins[0];
    let model = model_f64(&asset.skeleton);
    let skin_matrices: Vec<DMat4> = skin
        .joints
        .iter()
        .zip(&skin.inv_bind)
        .map(|(j, inv)| model[j.get()] * inv.as_dmat4())
        .collect();
    let matrix_error = skin_matrices
        .iter()
        .map(|s| {
            (*s - DMat4::IDENTITY)
                .to_cols_array()
                .iter()
                .fold(0.0_f64, |a, b| a.max(b.abs()))
        })
        .fold(0.0, f64::max);
    let mesh = &asset.meshes[0];
    let mut position_error = 0.0_f64;
    for (v, p) in mesh.positions.iter().enumerate() {
        let p = p.as_dvec3();
        let mut q = DVec3::ZERO;
        for inf in skin.influences.vertex(v) {
            q += f64::from(inf.weight) * skin_matrices[inf.joint as usize].transform_point3(p);
        }
        position_error = position_error.max((q - p).abs().max_element());
    }
    (matrix_error, position_error)
}

/// Asserts that every skin matrix is the identity and LBS reproduces every position,
/// both within 1e-6, evaluating the stored `f32` data in `f64`. The residue is the
/// `f32` rounding of the inverse bind matrices: half an ulp of their translations
/// (4.8e-7 for the corpus hand, whose joints lie up to 11 units from the origin).
fn assert_bind_pose(asset: &Asset, what: &str) {
    let (matrix, position) = bind_pose_errors(asset);
    assert!(
        matrix < 1e-6,
        "{what}: skin matrix differs from identity by {matrix:e}"
    );
    assert!(
        position < 1e-6,
        "{what}: bind pose moves a vertex by {position:e}"
    );
}

fn err<T: std::fmt::Debug>(result: Result<T, ImportError>) -> String {
    result.expect_err("should fail").to_string()
}

fn config(text: &str) -> Result<(SkinConfig, Vec<Warning>), ImportError> {
    parse_config(text, Path::new("skin.config"))
}

fn hierarchy(text: &str) -> Result<Vec<Option<usize>>, ImportError> {
    parse_hierarchy(text, Path::new("h.txt"))
}

fn rest(text: &str, joints: usize) -> Result<RestTransforms, ImportError> {
    parse_rest_transforms(text, Path::new("r.txt"), joints)
}

fn weights(text: &str, v: usize, j: usize) -> Result<(Influences, Vec<Warning>), ImportError> {
    parse_weights(text, Path::new("w.txt"), v, j)
}

fn inf(joint: u32, weight: f32) -> Influence {
    Influence { joint, weight }
}

#[test]
fn config_with_comments_case_and_unknown_options() {
    let text = "\u{feff}# header comment\r\n\r\n*MESHFILENAME\r\n  # comment between option and value\r\n\r\nmy mesh.obj  \r\n*jointHierarchyFilename\nh.txt\n*jointRestTransformsFilename\nr.txt\n*allLightsIntensity\n0.5\n*ikJointIds\n15, 19, 4, 8\n#18, 15, 4, 8\n*frobnicate\n42\n";
    let (cfg, warnings) = config(text).unwrap();
    let entry = |value: &str, line| {
        Some(ConfigEntry {
            value: value.to_string(),
            line,
        })
    };
    assert_eq!(cfg.mesh_filename, entry("my mesh.obj", 6));
    assert_eq!(cfg.joint_hierarchy_filename, entry("h.txt", 8));
    assert_eq!(cfg.joint_rest_transforms_filename, entry("r.txt", 10));
    assert_eq!(cfg.joint_weights_filename, None);
    assert_eq!(
        cfg.ik_joint_ids,
        Some(ConfigEntry {
            value: vec![15, 19, 4, 8],
            line: 14
        })
    );
    let other: Vec<(&str, &str, usize)> = cfg
        .other
        .iter()
        .map(|(n, e)| (n.as_str(), e.value.as_str(), e.line))
        .collect();
    assert_eq!(
        other,
        [("allLightsIntensity", "0.5", 12), ("frobnicate", "42", 17)]
    );
    assert_eq!(
        warnings,
        [Warning::Note {
            location: "skin.config:16".into(),
            message: "unknown option *frobnicate ignored".into()
        }]
    );
}

#[test]
fn config_errors_name_the_line() {
    assert_eq!(
            err(config("*meshFilename\n\n# c\n*jointHierarchyFilename\nh.txt\n")),
            "skin.config:1: *meshFilename has no value: the next line that is not blank or a comment (line 4) starts another option"
        );
    assert_eq!(
        err(config("*meshFilename\na.obj\n*IKJointIDs\n# none\n")),
        "skin.config:3: *IKJointIDs has no value: the file ends"
    );
    assert_eq!(
        err(config("*meshFilename\na.obj\n*MeshFileName\nb.obj\n")),
        "skin.config:3: *MeshFileName is given twice (first on line 1)"
    );
    assert_eq!(
        err(config("*meshFilename\na.obj\nb.obj\n")),
        "skin.config:3: expected an `*option` line, a `#` comment or a blank line, found \"b.obj\""
    );
    assert_eq!(
            err(config("*meshFilename a.obj\n")),
            "skin.config:1: expected an option name alone on its line (the value goes on the next line), found \"*meshFilename a.obj\""
        );
    assert_eq!(
        err(config("\n*\nx\n")),
        "skin.config:2: expected an option name after `*`, found \"*\""
    );
    assert_eq!(
        err(config("*IKJointIDs\n\n1, 2; 3\n")),
        "skin.config:3: *IKJointIDs: expected a joint index, `,` or `:`, found \"; 3\""
    );
}

#[test]
fn joint_lists_follow_listio() {
    assert_eq!(parse_joint_list("15, 19, 4, 8"), Ok(vec![15, 19, 4, 8]));
    assert_eq!(
        parse_joint_list("6 10,14 ,22\t18"),
        Ok(vec![6, 10, 14, 22, 18])
    );
    assert_eq!(
        parse_joint_list("0:3, 7 9 : 10"),
        Ok(vec![0, 1, 2, 3, 7, 9, 10])
    );
    assert_eq!(parse_joint_list("5:5,"), Ok(vec![5]));
    assert_eq!(parse_joint_list("1,,2,"), Ok(vec![1, 2]));
    assert_eq!(parse_joint_list("  "), Ok(vec![]));
    assert_eq!(
        parse_joint_list("3:1"),
        Err("the range 3:1 runs backwards".into())
    );
    assert_eq!(
        parse_joint_list(":2"),
        Err("a `:` range needs a number before it".into())
    );
    assert_eq!(
        parse_joint_list("2:, 3"),
        Err("the range 2: needs a number after `:`".into())
    );
    assert_eq!(
        parse_joint_list("1, -1"),
        Err("joint index -1 is negative (indices are 0-based)".into())
    );
    assert_eq!(
        parse_joint_list("1 x"),
        Err("expected a joint index, `,` or `:`, found \"x\"".into())
    );
    assert_eq!(
        parse_joint_list("0:4000000000"),
        Err(format!("more than {MAX_LIST_LEN} joint indices"))
    );
    assert!(parse_joint_list("99999999999999999999").is_err());
}

#[test]
fn hierarchy_parses_any_order_and_checks_the_tree() {
    assert_eq!(
        hierarchy("1 3 -1 2").unwrap(),
        [Some(1), Some(3), None, Some(2)]
    );
    assert_eq!(
        hierarchy("# c\n-1, 0,\n0\n").unwrap(),
        [None, Some(0), Some(0)]
    );
    assert_eq!(err(hierarchy(" \n")), "h.txt: the file is empty");
    assert_eq!(
        err(hierarchy("-1\n0 x\n")),
        "h.txt:2:3: parent index \"x\" is not a number"
    );
    assert_eq!(
        err(hierarchy("-1\n0\n-2\n")),
        "h.txt:3: joint 2 has parent -2: the root's parent is -1, every other is a joint index"
    );
    assert_eq!(
        err(hierarchy("-1 0\n5\n")),
        "h.txt:2: joint 2 has parent 5, but there are only 3 joints (0..=2)"
    );
    assert_eq!(
        err(hierarchy("-1\n1\n")),
        "h.txt:2: joint 1 is its own parent"
    );
    // Joints 1 -> 2 -> 3 -> 1 loop; joint 1 is on line 2.
    assert_eq!(
        err(hierarchy("-1\n2\n3\n1\n")),
        "h.txt:2: invalid skeleton: joints [3, 2, 1] form a parent cycle"
    );
    assert_eq!(
            err(hierarchy("-1 0\n-1\n")),
            "h.txt:2: joint 2 is a second root (parent -1) besides joint 0: the rig must have exactly one root"
        );
}

#[test]
fn rest_transforms_are_a_stream() {
    // 2 joints: 6 translations, 6 angles, 6 orients, broken over lines at random,
    // then orders written without spaces and in upper case.
    let text = "1 2 3 4\n5 6 10 20 30 40 50 60\n\n0.5 0 0\n0 0 -0.5e1\n  ZXYxyz";
    let r = rest(text, 2).unwrap();
    assert_eq!(
        r.translations,
        [DVec3::new(1.0, 2.0, 3.0), DVec3::new(4.0, 5.0, 6.0)]
    );
    assert_eq!(
        r.rest_angles_deg,
        [DVec3::new(10.0, 20.0, 30.0), DVec3::new(40.0, 50.0, 60.0)]
    );
    assert_eq!(
        r.joint_orients_deg,
        [DVec3::new(0.5, 0.0, 0.0), DVec3::new(0.0, 0.0, -5.0)]
    );
    assert_eq!(r.rotate_orders, [EulerOrder::Zxy, EulerOrder::Xyz]);
    assert!(r.rotate_orders_given);
    let plain = rest("0 0 0\n0 0 0\n0 0 0\n\n", 1).unwrap();
    assert_eq!(plain.rotate_orders, [EulerOrder::Xyz]);
    assert!(!plain.rotate_orders_given);
}

#[test]
fn rest_transform_errors_name_the_line_and_token() {
    let numbers = "0 0 0 0 0 0\n0 0 0 0 0 0\n0 0 0 0 0 0\n";
    assert_eq!(
            err(rest(&format!("{numbers}xyz abc\n"), 2)),
            "r.txt:4: expected a rotate order (xyz, yzx, zxy, xzy, yxz or zyx) for joint 1, found \"abc\""
        );
    assert_eq!(
        err(rest(&format!("{numbers}xyz\n"), 2)),
        "r.txt:4: truncated: rotate orders for 1 of 2 joints: give one per joint or none"
    );
    assert_eq!(
        err(rest(&format!("{numbers}xyz xyz\n0\n"), 2)),
        "r.txt:5: expected the end of the file after 2 rotate orders, found \"0\""
    );
    assert_eq!(
            err(rest("0 0 0 0 0 0\n0 0 0 0 0 0\n", 2)),
            "r.txt:2: truncated: 12 numbers for 2 joints, expected 18: 6 translations, 6 rest angles and 6 joint orients"
        );
    // The orders line where the joint orients should be.
    assert_eq!(
        err(rest("0 0 0 0 0 0\n0 0 0 0 0 0\nxyz xyz\n", 2)),
        "r.txt:3:1: joint orient \"xyz\" is not a number"
    );
    assert_eq!(
        err(rest("0 0 0 0 0 0\n0 0 0 0 0 1,5\n", 2)),
        "r.txt:2:11: rest angle \"1,5\" is not a number"
    );
    assert_eq!(
        err(rest("0 0 0\nNaN 0 0\n0 0 0\n", 1)),
        "r.txt:2:1: rest angle \"NaN\" is not finite"
    );
    assert_eq!(
        err(rest("0 1e39 0\n0 0 0\n0 0 0\n", 1)),
        "r.txt:1:3: translation \"1e39\" is out of range for f32"
    );
    assert_eq!(err(rest("\n\n", 1)), "r.txt: the file is empty");
}

/// Row-major 4×4 matrices written out by hand, the reference for the formula.
type M4 = [[f64; 4]; 4];

fn mul(a: &M4, b: &M4) -> M4 {
    let mut out = [[0.0; 4]; 4];
    for (r, row) in out.iter_mut().enumerate() {
        for (c, value) in row.iter_mut().enumerate() {
            *value = (0..4).map(|k| a[r][k] * b[k][c]).sum();
        }
    }
    out
}

fn rx(deg: f64) -> M4 {
    let (s, c) = deg.to_radians().sin_cos();
    [
        [1.0, 0.0, 0.0, 0.0],
        [0.0, c, -s, 0.0],
        [0.0, s, c, 0.0],
        [0.0, 0.0, 0.0, 1.0],
    ]
}

fn ry(deg: f64) -> M4 {
    let (s, c) = deg.to_radians().sin_cos();
    [
        [c, 0.0, s, 0.0],
        [0.0, 1.0, 0.0, 0.0],
        [-s, 0.0, c, 0.0],
        [0.0, 0.0, 0.0, 1.0],
    ]
}

fn rz(deg: f64) -> M4 {
    let (s, c) = deg.to_radians().sin_cos();
    [
        [c, -s, 0.0, 0.0],
        [s, c, 0.0, 0.0],
        [0.0, 0.0, 1.0, 0.0],
        [0.0, 0.0, 0.0, 1.0],
    ]
}

fn translate(t: [f64; 3]) -> M4 {
    [
        [1.0, 0.0, 0.0, t[0]],
        [0.0, 1.0, 0.0, t[1]],
        [0.0, 0.0, 1.0, t[2]],
        [0.0, 0.0, 0.0, 1.0],
    ]
}

/// The table of csci520_format.md, section 4.
fn euler_matrix(order: EulerOrder, a: [f64; 3]) -> M4 {
    let (x, y, z) = (rx(a[0]), ry(a[1]), rz(a[2]));
    match order {
        EulerOrder::Xyz => mul(&mul(&z, &y), &x),
        EulerOrder::Yzx => mul(&mul(&x, &z), &y),
        EulerOrder::Zxy => mul(&mul(&y, &x), &z),
        EulerOrder::Xzy => mul(&mul(&y, &z), &x),
        EulerOrder::Yxz => mul(&mul(&z, &x), &y),
        EulerOrder::Zyx => mul(&mul(&x, &y), &z),
    }
}

/// local = T(translate) · R_xyz(jointOrient) · R_order(angles).
fn naive_local(t: [f64; 3], orient: [f64; 3], angles: [f64; 3], order: EulerOrder) -> M4 {
    mul(
        &mul(&translate(t), &euler_matrix(EulerOrder::Xyz, orient)),
        &euler_matrix(order, angles),
    )
}

fn assert_matrix_close(got: Mat4, expected: &M4, tolerance: f64, what: &str) {
    let got = got.as_dmat4();
    for (r, row) in expected.iter().enumerate() {
        for (c, &e) in row.iter().enumerate() {
            let g = got.col(c)[r];
            assert!(
                (g - e).abs() < tolerance,
                "{what}: [{r}][{c}] is {g}, expected {e} (difference {:e})\n{got}\nvs {expected:?}",
                (g - e).abs()
            );
        }
    }
}

#[test]
fn local_transform_matches_the_matrix_product() {
    let t = [0.3, -1.25, 2.0];
    let orient = [5.0, -10.0, 20.0];
    let angles = [30.0, 45.0, 15.0];
    for order in EulerOrder::ALL {
        let got = rest_local_transform(t.into(), orient.into(), angles.into(), order);
        assert_eq!(got.scale, Vec3::ONE);
        assert!(got.rotation.w >= 0.0);
        // f32 storage: 1e-6 relative is a few ulps of these magnitudes.
        assert_matrix_close(
            got.to_mat4(),
            &naive_local(t, orient, angles, order),
            1e-6,
            order.as_str(),
        );
    }
    // Orders matter: the same angles in another order give another rotation.
    let a = euler_rotation(EulerOrder::Xyz, DVec3::from(angles));
    let b = euler_rotation(EulerOrder::Zxy, DVec3::from(angles));
    assert!(a.angle_between(b) > 0.1);
}

#[test]
fn weights_header_on_one_line_or_two() {
    let two = "3\n2\n0 0 1.0\n1 0 0.25\n1 1 0.75\n2 1 1.0";
    let one = "3 2\r\n0 0 1.0\r\n\r\n1 1 0.75  \r\n1 0 0.25\r\n2 1 1.0\r\n";
    let (a, wa) = weights(two, 3, 2).unwrap();
    let (b, wb) = weights(one, 3, 2).unwrap();
    assert_eq!(a, b);
    assert!(wa.is_empty() && wb.is_empty(), "{wa:?} {wb:?}");
    assert_eq!(a.vertex(1), [inf(1, 0.75), inf(0, 0.25)]);
}

#[test]
fn weights_repairs_are_reported() {
    // Vertex 0: duplicate entries summed (0.25 + 0.25) and zero weight dropped;
    // vertex 1: sums to 2 (renormalized); vertex 2: no entry; vertex 3: off by 5e-5
    // (kept as written).
    let text = "4 3\n0 0 0.25\n0 1 0.5\n0 0 0.25\n0 2 0\n1 2 1.5\n1 0 0.5\n3 1 0.99995\n";
    let (influences, warnings) = weights(text, 4, 3).unwrap();
    assert_eq!(influences.vertex(0), [inf(0, 0.5), inf(1, 0.5)]);
    assert_eq!(influences.vertex(1), [inf(2, 0.75), inf(0, 0.25)]);
    assert_eq!(influences.vertex(2), []);
    assert_eq!(influences.vertex(3), [inf(1, 0.99995)]);
    assert_eq!(
            warnings,
            [
                Warning::Note {
                    location: "w.txt:4".into(),
                    message: "1 duplicate (vertex, joint) entries were added to the first entry of their pair".into()
                },
                Warning::WeightsRenormalized {
                    source: "w.txt".into(),
                    rows: 1,
                    max_row_sum_error: 1.0
                },
                Warning::Note {
                    location: "w.txt".into(),
                    message: "1 of 4 vertices (the first is vertex 2) have no weight entry: they are bound to no joint".into()
                },
            ]
        );
}

#[test]
fn weight_errors_name_the_line() {
    assert_eq!(
        err(weights("2 2\n0 0 1\n1 1 1e-320\n", 2, 2)),
        "w.txt:3: the weights of vertex 1 sum to 1e-320, too small to renormalize"
    );
    assert_eq!(
        err(weights("5\n2\n0 0 1\n", 4, 2)),
        "w.txt:1: the header declares 5 rows, but the mesh has (OBJ `v` lines) 4"
    );
    assert_eq!(
        err(weights("4\n3\n0 0 1\n", 4, 2)),
        "w.txt:2: the header declares 3 columns, but the hierarchy has joints: 2"
    );
    assert_eq!(
            err(weights("4 2 0 0 1\n", 4, 2)),
            "w.txt:1: expected the end of the header line (`rows cols`; entries start on the next line), found \"0\""
        );
    assert_eq!(
        err(weights("four 2\n", 4, 2)),
        "w.txt:1: row count \"four\" is not a number"
    );
    assert_eq!(
        err(weights("4\n", 4, 2)),
        "w.txt:1: truncated: the file ends where the column count of the header `rows cols` was expected"
    );
    assert_eq!(err(weights("", 4, 2)), "w.txt: the file is empty");
    assert_eq!(
        err(weights("4 2\n0 0 1\n\n4 1 1\n", 4, 2)),
        "w.txt:4:1: vertex index 4 is out of range: there are 4 vertices"
    );
    assert_eq!(
        err(weights("4 2\n0 -1 1\n", 4, 2)),
        "w.txt:2:3: joint index -1 is out of range: there are 2 joints"
    );
    assert_eq!(
        err(weights("4 2\n0 0 1\n1 1\n", 4, 2)),
        "w.txt:3: expected an entry `vertex joint weight`, found \"1 1\""
    );
    assert_eq!(
        err(weights("4 2\n0 0.5 1\n", 4, 2)),
        "w.txt:2:3: joint \"0.5\" is not a number"
    );
    assert_eq!(
        err(weights("4 2\n0 0 -0.5\n", 4, 2)),
        "w.txt:2:5: weight -0.5 is negative"
    );
    assert_eq!(
        err(weights("4 2\n0 0 nan\n", 4, 2)),
        "w.txt:2:5: weight \"nan\" is not finite"
    );
    assert_eq!(
        err(weights("4 2\n0 0 1e308\n0 1 1e308\n", 4, 2)),
        "w.txt:2: the weights of vertex 0 sum to more than f64 holds"
    );
}

/// The chain fixture's files, in file numbering (see fixtures/README.md).
const CHAIN_PARENTS: [Option<usize>; 4] = [Some(1), Some(3), None, Some(2)];
const CHAIN_T: [[f64; 3]; 4] = [
    [0.0, 0.5, 0.0],
    [0.0, 0.75, 0.0],
    [0.0, 1.0, 0.0],
    [0.0, 1.0, 0.0],
];
const CHAIN_ANGLES: [[f64; 3]; 4] = [
    [0.0; 3],
    [0.0, 0.0, -20.0],
    [0.0, 15.0, 0.0],
    [30.0, 45.0, 15.0],
];
const CHAIN_ORIENT: [[f64; 3]; 4] = [[0.0; 3], [10.0, 0.0, 0.0], [0.0; 3], [5.0, -10.0, 20.0]];
const CHAIN_ORDER: [EulerOrder; 4] = [
    EulerOrder::Xyz,
    EulerOrder::Xyz,
    EulerOrder::Xyz,
    EulerOrder::Zxy,
];

/// Recursive FK over the file numbering: global(i) = global(parent) · local(i).
fn naive_global(f: usize) -> M4 {
    let local = naive_local(CHAIN_T[f], CHAIN_ORIENT[f], CHAIN_ANGLES[f], CHAIN_ORDER[f]);
    match CHAIN_PARENTS[f] {
        Some(p) => mul(&naive_global(p), &local),
        None => local,
    }
}

#[test]
fn chain_fixture_is_sorted_parents_first_and_remapped() {
    let rig = import_folder(&Path::new(FIXTURES).join("chain")).unwrap();
    assert!(
        rig.imported.warnings.is_empty(),
        "{:?}",
        rig.imported.warnings
    );
    let asset = &rig.imported.asset;
    assert_eq!(asset.name, "chain");
    let sk = &asset.skeleton;
    let names: Vec<&str> = sk.joints().iter().map(|j| j.name.as_str()).collect();
    assert_eq!(names, ["joint_2", "joint_3", "joint_1", "joint_0"]);
    assert_eq!(rig.file_index, [2, 3, 1, 0]);
    let parents: Vec<Option<u32>> = sk.parents().map(|p| p.map(|j| j.0)).collect();
    assert_eq!(parents, [None, Some(0), Some(1), Some(2)]);
    // Handles 0, 3 in the files are skeleton joints 3, 1.
    assert_eq!(rig.ik_handles, [JointIndex(3), JointIndex(1)]);
    assert_eq!(
        rig.rotate_orders,
        [
            EulerOrder::Xyz,
            EulerOrder::Zxy,
            EulerOrder::Xyz,
            EulerOrder::Xyz
        ]
    );
    assert_eq!(rig.rest_angles_deg[1], DVec3::new(30.0, 45.0, 15.0));
    assert_eq!(rig.joint_orients_deg[2], DVec3::new(10.0, 0.0, 0.0));
    // Model-space rest matrices against recursive FK over the file numbering.
    for (k, m) in sk.model_rest_matrices().into_iter().enumerate() {
        assert_matrix_close(m, &naive_global(rig.file_index[k]), 1e-5, names[k]);
    }
    // Influences: per output vertex (8 `v` lines + 2 UV-seam copies of v 5 and 6),
    // joints in skeleton numbering, largest first.
    let mesh = &asset.meshes[0];
    assert_eq!(mesh.vertex_count(), 10);
    assert_eq!(mesh.source_vertex_count(), 8);
    let skin = &asset.skins[0];
    assert_eq!(skin.joints, (0..4).map(JointIndex).collect::<Vec<_>>());
    let inf_of = |v: usize| skin.influences.vertex(v).to_vec();
    assert_eq!(inf_of(0), [inf(0, 1.0)]);
    assert_eq!(inf_of(2), [inf(1, 0.75), inf(0, 0.25)]);
    assert_eq!(inf_of(4), [inf(1, 0.5), inf(2, 0.5)]);
    assert_eq!(inf_of(6), [inf(3, 0.6), inf(2, 0.4)]);
    for (v, &s) in mesh.source_vertex.iter().enumerate() {
        assert_eq!(inf_of(v), inf_of(s as usize), "output vertex {v}");
    }
    assert_eq!(mesh.source_vertex[8..], [4, 5]);
    assert_bind_pose(asset, "chain");
}

#[test]
fn absent_or_unnamed_weights_give_an_unskinned_rig() {
    let dir = Path::new(FIXTURES).join("variants");
    let absent = import(&dir.join("absent_weights.config")).unwrap();
    assert!(absent.imported.asset.skins.is_empty());
    assert_eq!(absent.imported.asset.skeleton.len(), 4);
    assert_eq!(absent.imported.warnings.len(), 1);
    let text = absent.imported.warnings[0].to_string();
    assert!(
            text.ends_with("absent_weights.config:9: *jointWeightsFilename names \"absent_jointWeights.txt\", which does not exist: the rig has no skin weights; imported the skeleton and an unskinned mesh"),
            "{text}"
        );
    let unnamed = import(&dir.join("no_weights_option.config")).unwrap();
    assert!(unnamed.imported.asset.skins.is_empty());
    let text = unnamed.imported.warnings[0].to_string();
    assert!(
            text.ends_with("no_weights_option.config: no *jointWeightsFilename option: the rig has no skin weights; imported the skeleton and an unskinned mesh"),
            "{text}"
        );
    assert_eq!(unnamed.ik_handles, [JointIndex(3)]);
}

#[test]
fn import_errors_name_the_config_line() {
    let dir = Path::new(FIXTURES).join("variants");
    let text = err(import(&dir.join("missing_rest.config")));
    assert!(
            text.contains("missing_rest.config:8: *jointRestTransformsFilename names \"missing_jointRestTransforms.txt\", which cannot be read ("),
            "{text}"
        );
    let text = err(import(&dir.join("handle_out_of_range.config")));
    assert!(
        text.contains("handle_out_of_range.config:11: *IKJointIDs: joint 4 does not exist: ")
            && text.ends_with("jointHierarchy.txt has 4 joints (0..=3)"),
        "{text}"
    );
    let text = err(import(&dir.join("no_such.config")));
    assert!(text.contains("no_such.config: cannot read: "), "{text}");
}

/// (folder, J, V, largest influence count (`None`: no weights), IK handles in file
/// numbering).
type CorpusRig = (&'static str, usize, usize, Option<usize>, &'static [usize]);

#[test]
fn corpus_rigs_import() {
    // The one CI rule (rigport-testkit): skip when absent, fail in CI.
    if rigport_testkit::corpus("2_csci520_ik_skinning").is_none() {
        return;
    }
    // As csci520_format.md states them.
    let rigs: [CorpusRig; 4] = [
        ("tydia/armadillo", 22, 5002, Some(5), &[15, 19, 4, 8]),
        ("tydia/hand", 23, 2673, Some(7), &[6, 10, 14, 22, 18]),
        ("tydia/dragon", 28, 38615, None, &[3, 7, 9, 11, 12, 23, 27]),
        ("shreyabhaumik/star", 12, 12, Some(4), &[4, 6, 9, 11]),
    ];
    for (dir, joints, vertices, max_influences, handles) in rigs {
        let config = Path::new(CORPUS).join(dir).join("skin.config");
        let start = std::time::Instant::now();
        let rig = import(&config).unwrap_or_else(|e| panic!("{e}"));
        println!("{dir}: {:?}", start.elapsed());
        for w in &rig.imported.warnings {
            println!("  warning: {w}");
        }
        let asset = &rig.imported.asset;
        assert!(asset.validate().is_ok());
        assert_eq!(asset.skeleton.len(), joints, "{dir}");
        assert_eq!(asset.meshes[0].source_vertex_count(), vertices, "{dir}");
        let file_handles: Vec<usize> = rig
            .ik_handles
            .iter()
            .map(|h| rig.file_index[h.get()])
            .collect();
        assert_eq!(file_handles, handles, "{dir}");
        assert_eq!(rig.rotate_orders.len(), joints);
        // The staged hierarchies are already parents-first: the order is kept.
        assert_eq!(rig.file_index, (0..joints).collect::<Vec<_>>(), "{dir}");
        match max_influences {
            Some(max) => {
                assert!(rig.imported.warnings.is_empty(), "{dir}");
                let skin = &asset.skins[0];
                assert_eq!(skin.influences.max_per_vertex(), max, "{dir}");
                for row in skin.influences.rows() {
                    assert!(!row.is_empty(), "{dir}");
                    assert!(row.windows(2).all(|w| w[0].weight >= w[1].weight));
                }
                assert_bind_pose(asset, dir);
            }
            None => {
                assert!(asset.skins.is_empty(), "{dir}");
                // The dragon's OBJ mixes `f a b c` with `f a/t ...` faces (a note
                // from the OBJ reader), then the missing weights.
                let texts: Vec<String> = rig
                    .imported
                    .warnings
                    .iter()
                    .map(ToString::to_string)
                    .collect();
                assert_eq!(texts.len(), 2, "{texts:?}");
                assert!(
                    texts[0].ends_with(
                        "dragon.obj: some face corners have no texture coordinate; they get (0, 0)"
                    ),
                    "{texts:?}"
                );
                assert!(
                        texts[1].ends_with("skin.config:11: *jointWeightsFilename names \"jointWeights.txt\", which does not exist: the rig has no skin weights; imported the skeleton and an unskinned mesh"),
                        "{texts:?}"
                    );
            }
        }
    }
    // Armadillo: 4 joints use zxy (file joints 2, 6, 14, 18), the rest xyz; the others
    // are all xyz.
    let armadillo = import_folder(&Path::new(CORPUS).join("tydia/armadillo")).unwrap();
    let zxy: Vec<usize> = (0..22)
        .filter(|&k| armadillo.rotate_orders[k] == EulerOrder::Zxy)
        .map(|k| armadillo.file_index[k])
        .collect();
    assert_eq!(zxy, [2, 6, 14, 18]);
    assert!(armadillo
        .rotate_orders
        .iter()
        .all(|o| matches!(o, EulerOrder::Xyz | EulerOrder::Zxy)));
}

proptest::proptest! {
    #[test]
    fn parsers_never_panic_on_random_text(
        text in "(\\*|#|-?[0-9]{1,3}|[ ,:.eE]|xyz|ZxY|nan|inf|\r?\n|[a-z]|é|\u{3000}|\u{feff}){0,200}",
        vertices in 0_usize..6,
        joints in 0_usize..5,
    ) {
        let path = Path::new("r.txt");
        let _ = parse_config(&text, path);
        let _ = parse_joint_list(&text);
        if let Ok(parents) = parse_hierarchy(&text, path) {
            proptest::prop_assert!(parents_first_order(&parents).is_ok());
        }
        if let Ok(r) = parse_rest_transforms(&text, path, joints) {
            proptest::prop_assert_eq!(r.translations.len(), joints);
            proptest::prop_assert_eq!(r.rotate_orders.len(), joints);
        }
        if let Ok((influences, _)) = parse_weights(&text, path, vertices, joints) {
            proptest::prop_assert_eq!(influences.vertex_count(), vertices);
            proptest::prop_assert!(influences
                .entries()
                .iter()
                .all(|i| (i.joint as usize) < joints && i.weight > 0.0));
        }
    }
}
