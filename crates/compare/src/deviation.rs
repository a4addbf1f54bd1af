//! Deviations over a clip's frames: the largest and mean distance between paired vertices
//! and joints, the angle between paired joints' rotations (in the frame and relative to
//! the parent, which names the joint whose own rotation differs), where each largest one
//! is, and each reference vertex's largest deviation over the frames.

use glam::{DQuat, DVec3};

use crate::side::Posed;
use crate::vertex_map::VertexMap;

/// A reference joint paired with a candidate joint, with the pair of its parent (the
/// reference parent and that parent's candidate) when both have one.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct JointPair {
    /// Reference joint index.
    pub reference: usize,
    /// Candidate joint index.
    pub candidate: usize,
    /// The parents' pair, for rotations relative to the parent.
    pub parent: Option<(usize, usize)>,
}

/// A reference mesh paired with a candidate mesh, and their vertex map.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshPair {
    /// Reference mesh index.
    pub reference: usize,
    /// Candidate mesh index.
    pub candidate: usize,
    /// For each reference vertex, its candidate vertices.
    pub map: VertexMap,
}

impl MeshPair {
    /// How far reference vertex `v`, at `p`, is from the nearest of its candidate
    /// vertices among `candidate` positions (infinite when it has none).
    pub fn distance(&self, v: usize, p: DVec3, candidate: &[DVec3]) -> f64 {
        (self.map.of(v).iter())
            .filter_map(|&c| candidate.get(c as usize))
            .map(|c| c.distance(p))
            .fold(f64::INFINITY, f64::min)
    }
}

/// Where a largest deviation is: a frame (index into the times compared, and its time
/// in the reference's clip) and a joint or a mesh's vertex (reference indices).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct At {
    /// Index into the compared times.
    pub frame: usize,
    /// Seconds, on the reference's clock.
    pub time: f32,
    /// Reference mesh (0 for joints).
    pub mesh: usize,
    /// Reference vertex or joint.
    pub index: usize,
}

/// One quantity's largest and summed deviation, and where the largest is.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Deviation {
    /// The largest (metres or radians).
    pub max: f64,
    /// The sum over every sample.
    pub sum: f64,
    /// Samples.
    pub count: u64,
    /// Where the largest is (the first of equal ones).
    pub at: Option<At>,
}

impl Deviation {
    /// The mean, 0 without samples.
    pub fn mean(&self) -> f64 {
        if self.count == 0 {
            0.0
        } else {
            self.sum / self.count as f64
        }
    }

    fn add(&mut self, value: f64, at: At) {
        self.sum += value;
        self.count += 1;
        if value > self.max || self.at.is_none() {
            self.max = value;
            self.at = Some(at);
        }
    }

    /// Both, keeping the earlier place of equal largest ones (`self` holds earlier frames).
    fn merge(&mut self, later: &Deviation) {
        self.sum += later.sum;
        self.count += later.count;
        if later.max > self.max || (self.at.is_none() && later.at.is_some()) {
            self.max = later.max;
            self.at = later.at;
        }
    }
}

/// A clip's deviations over its frames.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ClipDeviation {
    /// Frames compared.
    pub frames: usize,
    /// Paired vertices' distances (metres).
    pub vertices: Deviation,
    /// Paired joints' distances (metres).
    pub joint_positions: Deviation,
    /// Angles between paired joints' rotations in the frame (radians).
    pub joint_rotations: Deviation,
    /// Angles between paired joints' rotations relative to their parents (radians): the
    /// largest names the joint whose own rotation differs.
    pub local_rotations: Deviation,
    /// Per mesh pair, per reference vertex, its largest distance over the frames.
    pub per_vertex: Vec<Vec<f64>>,
}

impl ClipDeviation {
    /// Empty, for `meshes`.
    pub(crate) fn new(meshes: &[MeshPair]) -> Self {
        Self {
            per_vertex: meshes.iter().map(|m| vec![0.0; m.map.len()]).collect(),
            ..Self::default()
        }
    }

    /// Adds one frame: `reference` and `candidate` evaluated at the same moment.
    pub(crate) fn add_frame(
        &mut self,
        frame: usize,
        time: f32,
        reference: &Posed,
        candidate: &Posed,
        joints: &[JointPair],
        meshes: &[MeshPair],
    ) {
        self.frames += 1;
        for pair in joints {
            let (r, c) = (pair.reference, pair.candidate);
            let (Some(rp), Some(cp), Some(rr), Some(cr)) = (
                reference.joint_positions.get(r),
                candidate.joint_positions.get(c),
                reference.joint_rotations.get(r),
                candidate.joint_rotations.get(c),
            ) else {
                continue;
            };
            let at = At {
                frame,
                time,
                mesh: 0,
                index: r,
            };
            self.joint_positions.add(rp.distance(*cp), at);
            self.joint_rotations.add(angle(*rr, *cr), at);
            let local = |posed: &Posed, parent: Option<usize>, joint: DQuat| match parent
                .and_then(|p| posed.joint_rotations.get(p))
            {
                Some(p) => p.inverse() * joint,
                None => joint,
            };
            let lr = local(reference, pair.parent.map(|p| p.0), *rr);
            let lc = local(candidate, pair.parent.map(|p| p.1), *cr);
            self.local_rotations.add(angle(lr, lc), at);
        }
        for (k, pair) in meshes.iter().enumerate() {
            let (Some(rv), Some(cv)) = (
                reference.positions.get(pair.reference),
                candidate.positions.get(pair.candidate),
            ) else {
                continue;
            };
            let per_vertex = &mut self.per_vertex[k];
            for (v, p) in rv.iter().enumerate() {
                let d = pair.distance(v, *p, cv);
                if !d.is_finite() {
                    continue;
                }
                if let Some(slot) = per_vertex.get_mut(v) {
                    *slot = slot.max(d);
                }
                self.vertices.add(
                    d,
                    At {
                        frame,
                        time,
                        mesh: pair.reference,
                        index: v,
                    },
                );
            }
        }
    }

    /// Both, `later` holding later frames.
    pub(crate) fn merge(&mut self, later: &ClipDeviation) {
        self.frames += later.frames;
        self.vertices.merge(&later.vertices);
        self.joint_positions.merge(&later.joint_positions);
        self.joint_rotations.merge(&later.joint_rotations);
        self.local_rotations.merge(&later.local_rotations);
        for (mine, theirs) in self.per_vertex.iter_mut().zip(&later.per_vertex) {
            for (a, b) in mine.iter_mut().zip(theirs) {
                *a = a.max(*b);
            }
        }
    }
}

/// The angle between two rotations (radians, in `[0, pi]`), accurate near 0 (from the
/// vector part of `a⁻¹ b`, not `acos` of a dot product).
pub fn angle(a: DQuat, b: DQuat) -> f64 {
    let d = a.inverse() * b;
    2.0 * d.xyz().length().atan2(d.w.abs())
}
