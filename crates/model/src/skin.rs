use glam::Mat4;

use crate::{JointIndex, MeshIndex};

/// How a skinned mesh's points follow its joints.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum SkinningMethod {
    /// Linear blend skinning (glTF's only method; UsdSkel `classicLinear`, its default).
    #[default]
    Lbs,
    /// Dual quaternion skinning as UsdSkel computes it (`dualQuaternion`).
    Dqs,
}

impl SkinningMethod {
    /// The `primvars:skel:skinningMethod` token UsdSkel uses for this method.
    pub fn usd_token(self) -> &'static str {
        match self {
            Self::Lbs => "classicLinear",
            Self::Dqs => "dualQuaternion",
        }
    }

    /// The method a UsdSkel `skinningMethod` token names.
    pub fn from_usd_token(token: &str) -> Option<Self> {
        match token {
            "classicLinear" => Some(Self::Lbs),
            "dualQuaternion" => Some(Self::Dqs),
            _ => None,
        }
    }
}

/// How a vertex with more influences than a writer's per-vertex limit drops the rest.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum InfluencesFit {
    /// Keep the largest weights, renormalized (what Blender, gltfpack and Assimp do).
    #[default]
    Truncate,
    /// Fit the kept weights to the full deformation over a pose set (`rigport-deform`'s
    /// `refit`).
    Refit,
}

/// One joint's weight on a vertex. `joint` indexes the owning [`SkinBinding::joints`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Influence {
    /// Index into the binding's joint palette.
    pub joint: u32,
    /// Weight, non-negative.
    pub weight: f32,
}

/// Sparse per-vertex influences of any count, stored compressed (CSR).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Influences {
    /// `offsets[v]..offsets[v + 1]` is vertex `v`'s range in `entries`; `len = vertices + 1`.
    offsets: Vec<u32>,
    entries: Vec<Influence>,
}

impl Influences {
    /// Builds from one list per vertex.
    pub fn from_rows<I, R>(rows: I) -> Self
    where
        I: IntoIterator<Item = R>,
        R: IntoIterator<Item = Influence>,
    {
        let mut out = Self {
            offsets: vec![0],
            entries: Vec::new(),
        };
        for row in rows {
            out.entries.extend(row);
            out.offsets.push(out.entries.len() as u32);
        }
        out
    }

    /// Rescales every row to sum to 1, as glTF requires and as viewers and both writers take
    /// weights, so that what rigport evaluates is what every file it writes holds. A row
    /// summing to 0 (an unskinned vertex) stays as it is and is not counted. Returns how
    /// many rows were off by more than `tolerance` and the largest `|sum - 1|`, for the
    /// importer's warning.
    ///
    /// ```
    /// use rigport_model::{Influence, Influences};
    /// let half = |joint| Influence { joint, weight: 0.45 };
    /// let mut rows = Influences::from_rows([vec![half(0), half(1)], vec![]]);
    /// let (off, worst) = rows.normalize(1e-3);
    /// assert_eq!((off, (worst * 100.0).round()), (1, 10.0));
    /// assert_eq!(rows.vertex(0)[1].weight, 0.5);
    /// ```
    pub fn normalize(&mut self, tolerance: f32) -> (usize, f32) {
        let (mut off, mut worst) = (0, 0.0_f32);
        for v in 0..self.vertex_count() {
            let row = &mut self.entries[self.offsets[v] as usize..self.offsets[v + 1] as usize];
            let sum: f32 = row.iter().map(|i| i.weight).sum();
            let dev = (sum - 1.0).abs();
            if dev > tolerance && sum > 0.0 {
                off += 1;
                worst = worst.max(dev);
            }
            if dev > f32::EPSILON && sum > 0.0 {
                row.iter_mut().for_each(|i| i.weight /= sum);
            }
        }
        (off, worst)
    }

    /// Number of vertices.
    pub fn vertex_count(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    /// The influences on vertex `v`.
    ///
    /// # Panics
    /// If `v >= vertex_count()`.
    pub fn vertex(&self, v: usize) -> &[Influence] {
        &self.entries[self.offsets[v] as usize..self.offsets[v + 1] as usize]
    }

    /// Every vertex's influences, in vertex order.
    pub fn rows(&self) -> impl ExactSizeIterator<Item = &[Influence]> + '_ {
        self.offsets
            .windows(2)
            .map(|w| &self.entries[w[0] as usize..w[1] as usize])
    }

    /// All influences of all vertices, flat.
    pub fn entries(&self) -> &[Influence] {
        &self.entries
    }

    /// The largest number of influences on one vertex.
    pub fn max_per_vertex(&self) -> usize {
        self.offsets
            .windows(2)
            .map(|w| (w[1] - w[0]) as usize)
            .max()
            .unwrap_or(0)
    }

    /// Reorders or duplicates vertices: output vertex `i` gets the influences of input
    /// vertex `map[i]`.
    ///
    /// # Panics
    /// If an entry of `map` is out of range.
    pub fn remap_vertices(&self, map: &[u32]) -> Self {
        Self::from_rows(map.iter().map(|&v| self.vertex(v as usize).iter().copied()))
    }
}

/// Binds a mesh to joints of the asset's skeleton with linear blend skinning data.
///
/// A vertex's skinned position is `Σ wᵢ · model(joints[jᵢ]) · inv_bind[jᵢ] · p`, with `p`
/// the mesh's bind-space position (glTF's and UsdSkel's rule, geomBindTransform = identity).
#[derive(Clone, Debug, PartialEq)]
pub struct SkinBinding {
    /// The skinned mesh.
    pub mesh: MeshIndex,
    /// The joint palette: influence `joint` values index this list.
    pub joints: Vec<JointIndex>,
    /// Inverse of each palette joint's model-space bind matrix (same length as `joints`).
    pub inv_bind: Vec<Mat4>,
    /// Per-vertex influences, one row per mesh vertex.
    pub influences: Influences,
    /// How the source skins this mesh (UsdSkel `primvars:skel:skinningMethod`; linear for
    /// every other format). Evaluators use it unless told otherwise.
    pub method: SkinningMethod,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csr_rows_round_trip() {
        let inf = |j, w| Influence {
            joint: j,
            weight: w,
        };
        let rows = vec![vec![inf(0, 1.0)], vec![], vec![inf(1, 0.25), inf(2, 0.75)]];
        let s = Influences::from_rows(rows.clone());
        assert_eq!(s.vertex_count(), 3);
        assert_eq!(s.max_per_vertex(), 2);
        let back: Vec<Vec<Influence>> = s.rows().map(|r| r.to_vec()).collect();
        assert_eq!(back, rows);
        let r = s.remap_vertices(&[2, 2, 0]);
        assert_eq!(r.vertex(1), rows[2].as_slice());
        assert_eq!(r.vertex(2), rows[0].as_slice());
    }
}
