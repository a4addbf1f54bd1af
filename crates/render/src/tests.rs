use super::*;
use rigport_model::{Joint, Mesh, Skeleton, Transform};

/// One joint and an unskinned unit square in the XY plane (model space), two CCW
/// triangles.
fn square() -> Asset {
    let skeleton = Skeleton::new(vec![Joint {
        name: "root".into(),
        parent: None,
        rest_local: Transform::IDENTITY,
    }])
    .unwrap();
    let mesh = Mesh {
        positions: vec![
            Vec3::new(-1.0, -1.0, 0.0),
            Vec3::new(1.0, -1.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(-1.0, 1.0, 0.0),
        ],
        triangles: vec![[0, 1, 2], [0, 2, 3]],
        source_vertex: vec![0, 1, 2, 3],
        ..Mesh::default()
    };
    Asset {
        skeleton,
        meshes: vec![mesh],
        ..Asset::default()
    }
}

#[test]
fn rest_pose_square_is_framed_with_the_margin() {
    let asset = square();
    let options = RenderOptions {
        width: 100,
        height: 100,
        skeleton: false,
        frame_counter: false,
        ..RenderOptions::default()
    };
    let frames = frame_list(&asset, None, None, None).unwrap();
    assert_eq!(frames.len(), 1);
    let pics = render_frames(&asset, None, &frames, None, &options).unwrap();
    let drawn: Vec<usize> = pics[0]
        .pixels()
        .iter()
        .enumerate()
        .filter(|(_, &c)| c != BACKGROUND)
        .map(|(i, _)| i)
        .collect();
    // An 8% margin on each side of 100 px leaves an 84 x 84 square.
    assert_eq!(drawn.len(), 84 * 84);
    assert_eq!(drawn.first(), Some(&(8 * 100 + 8)));
    // Facing the camera and the light alike: one colour.
    let c = pics[0].pixels()[drawn[0]];
    assert!(drawn.iter().all(|&i| pics[0].pixels()[i] == c));
    assert!(palette().contains(&c));

    // Seen edge-on from the side, the square is a vertical line of no area.
    let side = RenderOptions {
        view: View::Side,
        ..options
    };
    let pics = render_frames(&asset, None, &frames, None, &side).unwrap();
    assert!(pics[0].pixels().iter().all(|&c| c == BACKGROUND));
}

#[test]
fn both_is_twice_as_wide_and_overlay_is_drawn() {
    let asset = square();
    let options = RenderOptions {
        width: 40,
        height: 30,
        skinning: LBS_AND_DQS,
        ..RenderOptions::default()
    };
    let frames = frame_list(&asset, None, None, None).unwrap();
    let pics = render_frames(&asset, None, &frames, None, &options).unwrap();
    assert_eq!((pics[0].width(), pics[0].height()), (80, 30));
    assert!(pics[0].pixels().contains(&JOINT_COLOR));
    assert!(pics[0].pixels().contains(&TEXT_COLOR));
    assert!(matches!(
        render_frames(
            &asset,
            None,
            &frames,
            None,
            &RenderOptions {
                width: 0,
                ..options
            }
        ),
        Err(RenderError::Size { .. })
    ));
    assert!(matches!(
        render_clip_png(&asset, Some("walk"), None, &options),
        Err(RenderError::NoClip(_))
    ));
}

/// The column range `[min, max]` of non-background pixels and their count.
fn extent(fb: &Framebuffer) -> (u32, u32, usize) {
    let mut out = (u32::MAX, 0, 0);
    for y in 0..fb.height() {
        for x in 0..fb.width() {
            if fb.get(x, y) != Some(BACKGROUND) {
                out = (out.0.min(x), out.1.max(x), out.2 + 1);
            }
        }
    }
    out
}

#[test]
fn one_camera_frames_the_whole_clip() {
    use rigport_model::{Clip, Interpolation, JointIndex, Track, TrackTarget};
    let mut asset = square();
    asset.meshes[0].attached_to = Some(JointIndex(0));
    asset.clips.push(Clip {
        name: "slide".into(),
        tracks: vec![Track {
            target: TrackTarget::Translation(JointIndex(0)),
            interpolation: Interpolation::Linear,
            times: vec![0.0, 1.0],
            values: vec![0.0, 0.0, 0.0, 4.0, 0.0, 0.0],
        }],
    });
    let options = RenderOptions {
        width: 100,
        height: 100,
        skeleton: false,
        frame_counter: false,
        ..RenderOptions::default()
    };
    let clip = find_clip(&asset, Some("slide")).unwrap();
    let frames = frame_list(&asset, clip, Some(2.0), None).unwrap();
    let times: Vec<f32> = frames.iter().map(|f| f.time).collect();
    assert_eq!(times, vec![0.0, 0.5, 1.0]);
    let pics = render_frames(&asset, clip, &frames, None, &options).unwrap();
    // Bounds x in [-1, 5], y in [-1, 1]: 84 px over 6 units is 14 px per unit, so the
    // 2-unit square is 28 px wide in every frame and slides from the left margin (8) to
    // the right one (92, exclusive).
    let e: Vec<_> = pics.iter().map(extent).collect();
    assert_eq!(e[0], (8, 35, 28 * 28));
    assert_eq!(e[1], (36, 63, 28 * 28));
    assert_eq!(e[2], (64, 91, 28 * 28));
    // Only the chosen frames are framed: the last one alone fills the picture's width.
    let last = render_frames(&asset, clip, &frames[2..], None, &options).unwrap();
    assert_eq!(extent(&last[0]).2, 84 * 84);
    // Rendering again, or in a different split, gives the same pixels.
    let again = render_frames(&asset, clip, &frames, None, &options).unwrap();
    assert_eq!(pics, again);
}

/// The pixels of `color` in `fb`, as `(x, y)`.
fn pixels_of(fb: &Framebuffer, color: Rgba) -> Vec<(u32, u32)> {
    (0..fb.height())
        .flat_map(|y| (0..fb.width()).map(move |x| (x, y)))
        .filter(|&(x, y)| fb.get(x, y) == Some(color))
        .collect()
}

#[test]
fn markers_are_framed_and_drawn_on_top() {
    let asset = square();
    let options = RenderOptions {
        width: 100,
        height: 100,
        skeleton: false,
        frame_counter: false,
        ..RenderOptions::default()
    };
    let frames = frame_list(&asset, None, None, None).unwrap();
    let plain = render_frames(&asset, None, &frames, None, &options).unwrap();
    assert!(pixels_of(&plain[0], MARKER_COLOR).is_empty());
    // One marker far to the right, one behind the square's centre.
    let points = [Vec3::new(5.0, 0.0, 0.0), Vec3::new(0.0, 0.0, -3.0)];
    let marked = render_frames(&asset, None, &frames, Some(&points), &options).unwrap();
    let fb = &marked[0];
    // Bounds x in [-1, 5]: 14 px per unit from x = 8, so the far marker's centre is at
    // (92, 50) (a pixel corner) and the square spans columns 8..36.
    for (x, y) in [(91, 49), (92, 50), (91, 50), (92, 49)] {
        assert_eq!(fb.get(x, y), Some(MARKER_COLOR), "far marker at ({x}, {y})");
    }
    // The behind one is drawn over the square, depth ignored.
    assert_eq!(fb.get(21, 50), Some(MARKER_COLOR));
    // The crosshair is inside the picture, clear of its border.
    assert!(pixels_all(fb)
        .iter()
        .all(|&(x, y)| (1..99).contains(&x) && (1..99).contains(&y)));
    // The square got smaller to make room: 28 px instead of 84.
    let square_px = fb
        .pixels()
        .iter()
        .filter(|&&c| c != BACKGROUND && c != MARKER_COLOR)
        .count();
    assert!(square_px < 28 * 28, "{square_px}");
    // Markers move with time: a closure of time, evaluated at each frame's time.
    let moving = |t: f32, out: &mut Vec<Vec3>| out.push(Vec3::new(t, 0.0, 0.0));
    let at_zero = render_frames(&asset, None, &frames, Some(&moving), &options).unwrap();
    assert_eq!(at_zero[0].get(50, 50), Some(MARKER_COLOR));
    // Deterministic.
    let again = render_frames(&asset, None, &frames, Some(&points), &options).unwrap();
    assert_eq!(marked, again);
}

/// A closed box `[-1, 1] x [0, 3] x [-0.5, 0.5]`, unskinned, 12 triangles.
fn boxy() -> Asset {
    let mut asset = square();
    let (lo, hi) = (Vec3::new(-1.0, 0.0, -0.5), Vec3::new(1.0, 3.0, 0.5));
    let positions: Vec<Vec3> = (0..8)
        .map(|i| {
            Vec3::new(
                if i & 1 == 0 { lo.x } else { hi.x },
                if i & 2 == 0 { lo.y } else { hi.y },
                if i & 4 == 0 { lo.z } else { hi.z },
            )
        })
        .collect();
    let quads = [
        [0, 1, 3, 2],
        [4, 6, 7, 5],
        [0, 4, 5, 1],
        [2, 3, 7, 6],
        [0, 2, 6, 4],
        [1, 5, 7, 3],
    ];
    asset.meshes[0].triangles = quads
        .iter()
        .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
        .collect();
    asset.meshes[0].source_vertex = (0..8).collect();
    asset.meshes[0].positions = positions;
    asset
}

#[test]
fn perspective_keeps_the_silhouette_inside_and_is_deterministic() {
    let asset = boxy();
    let frames = frame_list(&asset, None, None, None).unwrap();
    for view in [View::Front, View::Side, View::Top, View::ThreeQuarter] {
        let ortho = RenderOptions {
            width: 120,
            height: 100,
            view,
            skeleton: false,
            frame_counter: false,
            ..RenderOptions::default()
        };
        let persp = RenderOptions {
            projection: Projection::PERSPECTIVE,
            ..ortho
        };
        let o = render_frames(&asset, None, &frames, None, &ortho).unwrap();
        let p = render_frames(&asset, None, &frames, None, &persp).unwrap();
        let (po, pp) = (extent(&o[0]), extent(&p[0]));
        // Inside the margin (8% of 120 px = 9.6 px per side), not empty, and no larger
        // than the orthographic picture, whose nearest face it draws at the same scale.
        assert!(pp.0 >= 9 && pp.1 <= 120 - 10, "{view:?}: columns {pp:?}");
        assert!(
            pp.2 > po.2 / 3 && pp.2 <= po.2 + 2 * 120,
            "{view:?}: {pp:?} vs {po:?}"
        );
        let rows: Vec<u32> = pixels_all(&p[0]).iter().map(|&(_, y)| y).collect();
        assert!(rows.iter().all(|&y| (8..=91).contains(&y)), "{view:?}");
        // Seen head-on along an axis, the box's near face hides the rest and is drawn at
        // the orthographic scale (checked below); from three-quarters the far parts shrink.
        if view == View::ThreeQuarter {
            assert!(o != p, "{view:?}: perspective differs from orthographic");
        }
        let again = render_frames(&asset, None, &frames, None, &persp).unwrap();
        assert!(p == again, "{view:?}: not deterministic");
        assert!(p[0].pixels().iter().all(|c| palette().contains(c)));
    }
    // Seen from the front, the near face (z = 0.5) hides the far one: the perspective
    // silhouette of a box seen head-on is its near face, drawn at the orthographic scale.
    let front = RenderOptions {
        width: 100,
        height: 100,
        skeleton: false,
        frame_counter: false,
        projection: Projection::PERSPECTIVE,
        ..RenderOptions::default()
    };
    let p = render_frames(&asset, None, &frames, None, &front).unwrap();
    let o = render_frames(
        &asset,
        None,
        &frames,
        None,
        &RenderOptions {
            projection: Projection::Orthographic,
            ..front
        },
    )
    .unwrap();
    let (cp, co) = (extent(&p[0]).2, extent(&o[0]).2);
    assert!(cp.abs_diff(co) <= 2 * 84, "{cp} vs {co}");
}

#[test]
fn perspective_shrinks_far_things_and_depth_test_keeps_the_near_one() {
    // Two equal squares facing the camera, the second 3 units farther and shifted right
    // so that the near one hides part of it.
    let near = square().meshes.remove(0);
    let mut far = near.clone();
    for p in &mut far.positions {
        *p += Vec3::new(1.0, 0.0, -3.0);
    }
    let options = RenderOptions {
        width: 100,
        height: 100,
        skeleton: false,
        frame_counter: false,
        projection: Projection::PERSPECTIVE,
        ..RenderOptions::default()
    };
    let mut a = square();
    a.meshes = vec![near.clone(), far.clone()];
    let mut b = square();
    b.meshes = vec![far, near];
    let frames = frame_list(&a, None, None, None).unwrap();
    let pa = render_frames(&a, None, &frames, None, &options).unwrap();
    let pb = render_frames(&b, None, &frames, None, &options).unwrap();
    // Facing the camera, each square is one shade of its mesh's colour.
    let color = |fb: &Framebuffer, base: Rgba| -> Rgba {
        fb.pixels()
            .iter()
            .copied()
            .find(|&c| (0..SHADE_LEVELS).any(|l| shade(base, l) == c))
            .unwrap()
    };
    let (a0, a1) = (color(&pa[0], MESH_COLORS[0]), color(&pa[0], MESH_COLORS[1]));
    let (b0, b1) = (color(&pb[0], MESH_COLORS[0]), color(&pb[0], MESH_COLORS[1]));
    // Drawn in either order, the near square wins the same pixels.
    assert_eq!(pixels_of(&pa[0], a0), pixels_of(&pb[0], b1));
    assert_eq!(pixels_of(&pa[0], a1), pixels_of(&pb[0], b0));
    // The far square is drawn smaller: fewer rows than the near one.
    let rows = |px: Vec<(u32, u32)>| {
        let (lo, hi) = px
            .iter()
            .fold((u32::MAX, 0), |(lo, hi), &(_, y)| (lo.min(y), hi.max(y)));
        hi + 1 - lo
    };
    let (near_rows, far_rows) = (rows(pixels_of(&pa[0], a0)), rows(pixels_of(&pa[0], a1)));
    assert!(
        far_rows + 10 < near_rows,
        "near {near_rows} rows, far {far_rows}"
    );
}

/// Every non-background pixel.
fn pixels_all(fb: &Framebuffer) -> Vec<(u32, u32)> {
    (0..fb.height())
        .flat_map(|y| (0..fb.width()).map(move |x| (x, y)))
        .filter(|&(x, y)| fb.get(x, y) != Some(BACKGROUND))
        .collect()
}

#[test]
fn geometry_behind_or_across_the_near_plane_does_not_panic() {
    // A camera framed on a small region near the origin, then a mesh, bones and markers
    // that reach behind the eye.
    let mut b = Bounds::default();
    b.add(Vec3::new(-1.0, -1.0, -1.0));
    b.add(Vec3::new(1.0, 1.0, 1.0));
    let camera = Camera::framing_with(View::Front, Projection::PERSPECTIVE, b, 64, 64, 0.08);
    let Lens::Perspective { eye_z, .. } = camera.lens else {
        panic!("{:?}", camera.lens);
    };
    let mut asset = square();
    asset.meshes[0].positions = vec![
        Vec3::new(-1.0, -1.0, 0.0),
        Vec3::new(1.0, -1.0, 0.0),
        Vec3::new(0.0, 1.0, eye_z + 10.0),
        Vec3::new(0.0, 0.0, eye_z),
        Vec3::new(0.0, 0.0, f32::NAN),
    ];
    asset.meshes[0].source_vertex = (0..5).collect();
    asset.meshes[0].triangles = vec![[0, 1, 2], [2, 3, 4], [0, 1, 3], [0, 3, 4]];
    let mut fb = Framebuffer::new(64, 64, BACKGROUND);
    let positions = [asset.meshes[0].positions.clone()];
    draw_meshes(&mut fb, &asset, &positions, &camera, &Surfaces::new(&asset));
    let drawn = pixels_all(&fb).len();
    assert!(drawn > 0, "the part in front of the near plane is drawn");
    let behind = Mat4::from_translation(Vec3::new(0.0, 0.0, eye_z + 5.0));
    draw_skeleton(&mut fb, &asset, &[behind], &camera);
    draw_markers(
        &mut fb,
        &[Vec3::new(0.0, 0.0, eye_z + 1.0), Vec3::NAN, Vec3::ZERO],
        &camera,
    );
    assert!(fb.pixels().contains(&MARKER_COLOR));
    assert!(!fb.pixels().contains(&JOINT_COLOR));
}

#[test]
fn palette_fits_a_gif() {
    let p = palette();
    assert!(p.len() <= 256);
    assert_eq!(p.last(), Some(&MARKER_COLOR));
    assert_eq!(p.iter().filter(|&&c| c == MARKER_COLOR).count(), 1);
    let mut sorted = p.clone();
    sorted.sort_unstable();
    sorted.dedup();
    assert!(sorted.len() > 4 * SHADE_LEVELS / 2);
}
