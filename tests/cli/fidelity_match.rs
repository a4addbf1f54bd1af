//! Vertex correspondence between two evaluations of one surface that split and weld its
//! vertices differently (rigport's glb against three's FBXLoader / ColladaLoader, which
//! build one vertex per polygon corner; a `.usda`'s control points against the glb), and
//! the per-frame deviation once matched.
//!
//! Each vertex of ours is paired with the reference vertex nearest to it in a key pose
//! (the rest pose as loaded, or a shared frame); among reference vertices equally near
//! (within [`TIE`] of the diagonal: a seam's copies of one point, or two control points at
//! one place), the one whose whole trajectory stays nearest is taken, so coincident points
//! that move apart are told apart by their motion, never by a tolerance.

/// Positions of every vertex at one time, `[x, y, z]` in metres.
pub type Points = Vec<[f64; 3]>;

/// Reference vertices closer than this (relative to the diagonal) to the nearest one count
/// as the same place: float32 positions of one point agree to about 1e-7.
const TIE: f64 = 1e-6;

fn dist(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>().sqrt()
}

/// The bounding-box diagonal of `points` (0 for none).
pub fn diagonal(points: &[[f64; 3]]) -> f64 {
    if points.is_empty() {
        return 0.0;
    }
    let (mut lo, mut hi) = ([f64::MAX; 3], [f64::MIN; 3]);
    for p in points {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    dist(&lo, &hi)
}

/// One evaluation: the key pose and the compared frames (same vertex count in each).
pub struct Evaluated {
    pub key: Points,
    pub frames: Vec<Points>,
}

/// What matching and comparing measured, relative to the reference key pose's diagonal.
#[derive(Debug, Clone, Copy, Default)]
pub struct Measured {
    /// Largest distance in the key pose between a vertex of ours and its match.
    pub key: f64,
    /// Largest distance over the frames.
    pub frames: f64,
    /// Frame index of `frames` (0 when there are none).
    pub worst_frame: usize,
}

/// Reference vertices with an identical key position and trajectory, kept once (three's
/// loaders repeat a control point at every polygon corner): indices of the kept ones.
fn distinct(reference: &Evaluated) -> Vec<usize> {
    let mut seen = std::collections::HashSet::new();
    (0..reference.key.len())
        .filter(|&i| {
            let mut bits: Vec<u64> = reference.key[i].iter().map(|x| x.to_bits()).collect();
            for f in &reference.frames {
                bits.extend(f[i].iter().map(|x| x.to_bits()));
            }
            seen.insert(bits)
        })
        .collect()
}

/// For each vertex of `ours`, the reference vertex it corresponds to (see the module doc).
/// `scale` is the diagonal that [`TIE`] is relative to.
fn correspondence(ours: &Evaluated, reference: &Evaluated, scale: f64) -> Vec<usize> {
    let mut order = distinct(reference);
    order.sort_by(|&a, &b| reference.key[a][0].total_cmp(&reference.key[b][0]));
    let xs: Vec<f64> = order.iter().map(|&i| reference.key[i][0]).collect();
    let tie = TIE * scale;
    let trajectory = |v: usize, r: usize| -> f64 {
        ours.frames
            .iter()
            .zip(&reference.frames)
            .map(|(o, t)| dist(&o[v], &t[r]))
            .fold(0.0, f64::max)
    };
    (0..ours.key.len())
        .map(|v| {
            let p = ours.key[v];
            // Sweep outward in x from p's place until x alone is farther than the best.
            let start = xs.partition_point(|&x| x < p[0]);
            let mut best = f64::MAX;
            let (mut lo, mut hi) = (start, start);
            loop {
                let left = lo > 0 && p[0] - xs[lo - 1] <= best + tie;
                let right = hi < xs.len() && xs[hi] - p[0] <= best + tie;
                if !left && !right {
                    break;
                }
                if left {
                    lo -= 1;
                    best = best.min(dist(&p, &reference.key[order[lo]]));
                }
                if right {
                    best = best.min(dist(&p, &reference.key[order[hi]]));
                    hi += 1;
                }
            }
            order[lo..hi]
                .iter()
                .copied()
                .filter(|&r| dist(&p, &reference.key[r]) <= best + tie)
                .min_by(|&a, &b| trajectory(v, a).total_cmp(&trajectory(v, b)))
                .expect("a reference vertex")
        })
        .collect()
}

/// Matches `ours` to `reference` and measures the largest deviation in the key pose and
/// over the frames, relative to the diagonal of the reference key pose.
///
/// # Panics
/// The reference has no vertex while ours has some, or the frame counts differ.
pub fn measure(ours: &Evaluated, reference: &Evaluated) -> Measured {
    assert_eq!(ours.frames.len(), reference.frames.len(), "frame counts");
    if ours.key.is_empty() {
        return Measured::default();
    }
    assert!(!reference.key.is_empty(), "no reference vertex to match");
    let scale = diagonal(&reference.key).max(1e-30);
    let map = correspondence(ours, reference, scale);
    let mut m = Measured::default();
    for (v, &r) in map.iter().enumerate() {
        m.key = m.key.max(dist(&ours.key[v], &reference.key[r]) / scale);
    }
    for (f, (o, t)) in ours.frames.iter().zip(&reference.frames).enumerate() {
        for (v, &r) in map.iter().enumerate() {
            let d = dist(&o[v], &t[r]) / scale;
            if d > m.frames {
                m.frames = d;
                m.worst_frame = f;
            }
        }
    }
    m
}

#[test]
fn coincident_reference_points_are_told_apart_by_their_motion() {
    // Two reference points at one place that move apart; ours follows the second.
    let reference = Evaluated {
        key: vec![[0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [1.0, 1.0, 1.0]],
        frames: vec![vec![[0.0, 0.0, 0.0], [0.0, 0.5, 0.0], [1.0, 1.0, 1.0]]],
    };
    let ours = Evaluated {
        key: vec![[1.0, 1.0, 1.0], [0.0, 0.0, 0.0]],
        frames: vec![vec![[1.0, 1.0, 1.0], [0.0, 0.5, 0.0]]],
    };
    let m = measure(&ours, &reference);
    assert_eq!(m.key, 0.0);
    assert_eq!(m.frames, 0.0);
    // A wrong motion is measured, relative to the diagonal (sqrt 3).
    let wrong = Evaluated {
        key: ours.key.clone(),
        frames: vec![vec![[1.0, 1.0, 1.0], [0.0, 0.2, 0.0]]],
    };
    let m = measure(&wrong, &reference);
    assert!((m.frames - 0.2 / 3f64.sqrt()).abs() < 1e-12, "{m:?}");
}
