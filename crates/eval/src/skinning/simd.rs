//! Runtime-dispatched AVX2 + FMA kernels for the skinning hot loops.
//!
//! The portable loops in [`crate::skinning`] and [`crate::dqs`] use glam, which compiles to
//! SSE2 on x86-64 (the baseline every x86-64 CPU has): four lanes and no fused
//! multiply-add. On CPUs with AVX2 and FMA (x86-64-v3: Intel since Haswell, AMD since
//! Excavator) these kernels blend two matrix columns per 8-lane instruction and fuse the
//! multiply-adds, about twice the work per cycle. The CPU is checked once (pulp caches the
//! answer); `pulp`'s feature tokens make the intrinsics safe to call, so the crate stays free
//! of `unsafe`. Each `try_*` function returns `false` when it did nothing (another target,
//! or a CPU without the features) and the caller runs its portable loop.
//!
//! Results differ from the portable loops only by rounding (fused vs separate multiply and
//! add, a different summation order of the final transform); the skinning tests compare
//! both against the scalar reference with the same tolerances.

use glam::{Mat4, Vec3};

use super::common::{Frame, Hemisphere};

#[cfg(test)]
thread_local! {
    /// Tests turn the kernels off on their thread to compare them with the portable loops.
    static PORTABLE_ONLY: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// Whether the SIMD kernels may run (always outside tests).
#[inline(always)]
fn enabled() -> bool {
    #[cfg(test)]
    if PORTABLE_ONLY.with(|c| c.get()) {
        return false;
    }
    true
}

/// LBS of a fixed-width chunk (`W` slots per vertex in `joints`/`weights`), as
/// `skinning::lbs_fixed`. Joint indices are valid (checked at setup).
#[inline]
pub(crate) fn try_lbs_fixed<const W: usize>(
    mats: &[Mat4],
    joints: &[u32],
    weights: &[f32],
    rest: &[Vec3],
    out: &mut [Vec3],
) -> bool {
    #[cfg(target_arch = "x86_64")]
    if let Some(simd) = x86::V3::try_new().filter(|_| enabled()) {
        simd.vectorize(
            #[inline(always)]
            || x86::lbs_fixed::<W>(simd, mats, joints, weights, rest, out),
        );
        return true;
    }
    let _ = (mats, joints, weights, rest, out);
    false
}

/// LBS of a chunk of CSR rows, as `skinning::lbs_sparse`: `offsets` (one more than `rest`)
/// index the full arrays, of which `joints`/`weights` start at `base`.
#[inline]
pub(crate) fn try_lbs_sparse(
    mats: &[Mat4],
    offsets: &[u32],
    base: usize,
    joints: &[u32],
    weights: &[f32],
    rest: &[Vec3],
    out: &mut [Vec3],
) -> bool {
    #[cfg(target_arch = "x86_64")]
    if let Some(simd) = x86::V3::try_new().filter(|_| enabled()) {
        simd.vectorize(
            #[inline(always)]
            || x86::lbs_sparse(simd, mats, offsets, base, joints, weights, rest, out),
        );
        return true;
    }
    let _ = (mats, offsets, base, joints, weights, rest, out);
    false
}

#[cfg(target_arch = "x86_64")]
mod x86 {
    use glam::{Mat4, Vec3};
    use pulp::cast;

    use crate::skinning::common::{Frame, Hemisphere, JointDq, MIN_REAL_LENGTH};
    pub(super) use pulp::x86::V3;
    use std::arch::x86_64::{__m128, __m256};

    /// A skinning matrix as two 8-lane halves: columns (x, y) and (z, w).
    #[inline(always)]
    fn halves(m: &Mat4) -> [__m256; 2] {
        cast::<[f32; 16], [__m256; 2]>(m.to_cols_array())
    }

    /// Accumulates `w · M` into the two halves of a blended matrix.
    #[inline(always)]
    fn blend(simd: V3, acc: &mut [__m256; 2], m: &Mat4, w: f32) {
        let [a, b] = halves(m);
        let w = simd.avx._mm256_set1_ps(w);
        acc[0] = simd.fma._mm256_fmadd_ps(a, w, acc[0]);
        acc[1] = simd.fma._mm256_fmadd_ps(b, w, acc[1]);
    }

    /// `B · (p, 1)` for a blended matrix in halves: `(x·c0 + z·c2) + (y·c1 + c3)`.
    #[inline(always)]
    fn apply(simd: V3, acc: &[__m256; 2], p: Vec3) -> Vec3 {
        let xy = simd
            .avx
            ._mm256_set_m128(simd.sse._mm_set1_ps(p.y), simd.sse._mm_set1_ps(p.x));
        let z1 = simd
            .avx
            ._mm256_set_m128(simd.sse._mm_set1_ps(1.0), simd.sse._mm_set1_ps(p.z));
        let r = simd
            .fma
            ._mm256_fmadd_ps(acc[1], z1, simd.avx._mm256_mul_ps(acc[0], xy));
        let r4: __m128 = simd.sse._mm_add_ps(
            simd.avx._mm256_castps256_ps128(r),
            simd.avx._mm256_extractf128_ps::<1>(r),
        );
        let [x, y, z, _] = cast::<__m128, [f32; 4]>(r4);
        Vec3::new(x, y, z)
    }

    #[inline(always)]
    pub(super) fn lbs_fixed<const W: usize>(
        simd: V3,
        mats: &[Mat4],
        joints: &[u32],
        weights: &[f32],
        rest: &[Vec3],
        out: &mut [Vec3],
    ) {
        let zero = simd.avx._mm256_setzero_ps();
        for (((j, w), p), o) in joints
            .chunks_exact(W)
            .zip(weights.chunks_exact(W))
            .zip(rest)
            .zip(out)
        {
            let mut acc = [zero; 2];
            for (&j, &w) in j.iter().zip(w) {
                if let Some(m) = mats.get(j as usize) {
                    blend(simd, &mut acc, m, w);
                }
            }
            *o = apply(simd, &acc, *p);
        }
    }

    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    pub(super) fn lbs_sparse(
        simd: V3,
        mats: &[Mat4],
        offsets: &[u32],
        base: usize,
        joints: &[u32],
        weights: &[f32],
        rest: &[Vec3],
        out: &mut [Vec3],
    ) {
        let zero = simd.avx._mm256_setzero_ps();
        for ((o2, p), o) in offsets.windows(2).zip(rest).zip(out) {
            let (a, b) = (o2[0] as usize - base, o2[1] as usize - base);
            let (Some(js), Some(ws)) = (joints.get(a..b), weights.get(a..b)) else {
                continue;
            };
            let mut acc = [zero; 2];
            for (&j, &w) in js.iter().zip(ws) {
                if let Some(m) = mats.get(j as usize) {
                    blend(simd, &mut acc, m, w);
                }
            }
            *o = apply(simd, &acc, *p);
        }
    }

    /// One joint's dual quaternion as `[real | dual]` and its scale/shear as
    /// `[diag | off]` (`JointDq` is `repr(C)`: real, dual, diag, off).
    #[inline(always)]
    fn joint_dq(d: &JointDq) -> [__m256; 2] {
        cast::<[[f32; 4]; 4], [__m256; 2]>([
            d.real.to_array(),
            d.dual.to_array(),
            d.scale.diag.to_array(),
            d.scale.off.to_array(),
        ])
    }

    /// Transposes eight 8-lane rows: lane `k` of row `i` becomes lane `i` of row `k`.
    #[inline(always)]
    fn transpose8(simd: V3, r: [__m256; 8]) -> [__m256; 8] {
        let a = simd.avx;
        let t = [
            a._mm256_unpacklo_ps(r[0], r[1]),
            a._mm256_unpackhi_ps(r[0], r[1]),
            a._mm256_unpacklo_ps(r[2], r[3]),
            a._mm256_unpackhi_ps(r[2], r[3]),
            a._mm256_unpacklo_ps(r[4], r[5]),
            a._mm256_unpackhi_ps(r[4], r[5]),
            a._mm256_unpacklo_ps(r[6], r[7]),
            a._mm256_unpackhi_ps(r[6], r[7]),
        ];
        let u = [
            a._mm256_shuffle_ps::<0x44>(t[0], t[2]),
            a._mm256_shuffle_ps::<0xEE>(t[0], t[2]),
            a._mm256_shuffle_ps::<0x44>(t[1], t[3]),
            a._mm256_shuffle_ps::<0xEE>(t[1], t[3]),
            a._mm256_shuffle_ps::<0x44>(t[4], t[6]),
            a._mm256_shuffle_ps::<0xEE>(t[4], t[6]),
            a._mm256_shuffle_ps::<0x44>(t[5], t[7]),
            a._mm256_shuffle_ps::<0xEE>(t[5], t[7]),
        ];
        [
            a._mm256_permute2f128_ps::<0x20>(u[0], u[4]),
            a._mm256_permute2f128_ps::<0x20>(u[1], u[5]),
            a._mm256_permute2f128_ps::<0x20>(u[2], u[6]),
            a._mm256_permute2f128_ps::<0x20>(u[3], u[7]),
            a._mm256_permute2f128_ps::<0x31>(u[0], u[4]),
            a._mm256_permute2f128_ps::<0x31>(u[1], u[5]),
            a._mm256_permute2f128_ps::<0x31>(u[2], u[6]),
            a._mm256_permute2f128_ps::<0x31>(u[3], u[7]),
        ]
    }

    /// `[Σ ±wₖ real | Σ ±wₖ dual]` and `[Σ wₖ diag | Σ wₖ off]` of one vertex's
    /// influences (pivot first, as `dqs::blend_fixed`).
    #[inline(always)]
    fn dq_blend<const SCALE: bool, H: Hemisphere>(
        simd: V3,
        frame: &Frame<'_>,
        h: H,
        j: &[u32],
        w: &[f32],
    ) -> [__m256; 2] {
        let zero = simd.avx._mm256_setzero_ps();
        let mut acc = [zero; 2];
        let Some(&pivot) = j.first() else {
            return acc;
        };
        let h = h.for_pivot(frame.dq, pivot as usize);
        for (&jk, &wk) in j.iter().zip(w) {
            let Some(d) = frame.dq.get(jk as usize) else {
                continue;
            };
            let [dq, sc] = joint_dq(d);
            let sw = simd.avx._mm256_set1_ps(wk * h.sign(d, jk as usize));
            acc[0] = simd.fma._mm256_fmadd_ps(dq, sw, acc[0]);
            if SCALE {
                let w = simd.avx._mm256_set1_ps(wk);
                acc[1] = simd.fma._mm256_fmadd_ps(sc, w, acc[1]);
            }
        }
        acc
    }

    /// Finishes eight vertices of a DQS block: `dq[l]` is lane `l`'s blended
    /// `[real | dual]`, `sc[l]` its blended `[diag | off]` scale/shear (used when `SCALE`);
    /// writes `o[l]` from rest point `r[l]` (`r` and `o` hold eight points).
    #[inline(always)]
    fn dq_apply8<const SCALE: bool>(
        simd: V3,
        dq: [__m256; 8],
        sc: [__m256; 8],
        r: &[Vec3; 8],
        o: &mut [Vec3; 8],
    ) {
        let (a, f) = (simd.avx, simd.fma);
        let min_n2 = a._mm256_set1_ps(MIN_REAL_LENGTH * MIN_REAL_LENGTH);
        let two = a._mm256_set1_ps(2.0);
        // Structure of arrays: one register per component, one lane per vertex.
        let [rx, ry, rz, rw, dx, dy, dz, dw] = transpose8(simd, dq);
        let lanes = |c: fn(&Vec3) -> f32| {
            cast::<[f32; 8], __m256>([
                c(&r[0]),
                c(&r[1]),
                c(&r[2]),
                c(&r[3]),
                c(&r[4]),
                c(&r[5]),
                c(&r[6]),
                c(&r[7]),
            ])
        };
        let (mut px, mut py, mut pz) = (lanes(|p| p.x), lanes(|p| p.y), lanes(|p| p.z));
        if SCALE {
            // Σ wₖ Sₖ p with S symmetric: diag (d0, d1, d2), off (xy, xz, yz).
            let [d0, d1, d2, _, oxy, oxz, oyz, _] = transpose8(simd, sc);
            let sx =
                f._mm256_fmadd_ps(oxz, pz, f._mm256_fmadd_ps(oxy, py, a._mm256_mul_ps(d0, px)));
            let sy =
                f._mm256_fmadd_ps(oyz, pz, f._mm256_fmadd_ps(d1, py, a._mm256_mul_ps(oxy, px)));
            let sz =
                f._mm256_fmadd_ps(d2, pz, f._mm256_fmadd_ps(oyz, py, a._mm256_mul_ps(oxz, px)));
            (px, py, pz) = (sx, sy, sz);
        }
        // As `dqs::apply4`: p + (rw u + r × u − dw r) · 2/|r|², u = r × p + d; a blend
        // with |r| below the threshold (or NaN) leaves p.
        let n2 = f._mm256_fmadd_ps(
            rw,
            rw,
            f._mm256_fmadd_ps(rz, rz, f._mm256_fmadd_ps(ry, ry, a._mm256_mul_ps(rx, rx))),
        );
        let valid = a._mm256_cmp_ps::<29>(n2, min_n2); // _CMP_GE_OQ
        let s = a._mm256_and_ps(valid, a._mm256_div_ps(two, n2));
        let cross = |ax, ay, az, bx, by, bz| {
            (
                f._mm256_fmsub_ps(ay, bz, a._mm256_mul_ps(az, by)),
                f._mm256_fmsub_ps(az, bx, a._mm256_mul_ps(ax, bz)),
                f._mm256_fmsub_ps(ax, by, a._mm256_mul_ps(ay, bx)),
            )
        };
        let (cx, cy, cz) = cross(rx, ry, rz, px, py, pz);
        let (ux, uy, uz) = (
            a._mm256_add_ps(cx, dx),
            a._mm256_add_ps(cy, dy),
            a._mm256_add_ps(cz, dz),
        );
        let (vx, vy, vz) = cross(rx, ry, rz, ux, uy, uz);
        let tx = f._mm256_fnmadd_ps(dw, rx, f._mm256_fmadd_ps(rw, ux, vx));
        let ty = f._mm256_fnmadd_ps(dw, ry, f._mm256_fmadd_ps(rw, uy, vy));
        let tz = f._mm256_fnmadd_ps(dw, rz, f._mm256_fmadd_ps(rw, uz, vz));
        let ox = cast::<__m256, [f32; 8]>(f._mm256_fmadd_ps(tx, s, px));
        let oy = cast::<__m256, [f32; 8]>(f._mm256_fmadd_ps(ty, s, py));
        let oz = cast::<__m256, [f32; 8]>(f._mm256_fmadd_ps(tz, s, pz));
        for (l, o) in o.iter_mut().enumerate() {
            *o = Vec3::new(ox[l], oy[l], oz[l]);
        }
    }

    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    pub(super) fn dqs_fixed<const W: usize, const SCALE: bool, H: Hemisphere>(
        simd: V3,
        frame: &Frame<'_>,
        h: H,
        joints: &[u32],
        weights: &[f32],
        rest: &[Vec3],
        out: &mut [Vec3],
    ) -> usize {
        let zero = simd.avx._mm256_setzero_ps();
        let mut done = 0;
        for (((j, w), r), o) in joints
            .chunks_exact(8 * W)
            .zip(weights.chunks_exact(8 * W))
            .zip(rest.chunks_exact(8))
            .zip(out.chunks_exact_mut(8))
        {
            let (Ok(r), Ok(o)) = (<&[Vec3; 8]>::try_from(r), <&mut [Vec3; 8]>::try_from(o)) else {
                break;
            };
            let mut dq = [zero; 8];
            let mut sc = [zero; 8];
            for l in 0..8 {
                let s = l * W..(l + 1) * W;
                [dq[l], sc[l]] = dq_blend::<SCALE, H>(simd, frame, h, &j[s.clone()], &w[s]);
            }
            dq_apply8::<SCALE>(simd, dq, sc, r, o);
            done += 8;
        }
        done
    }

    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    pub(super) fn dqs_sparse<const SCALE: bool, H: Hemisphere>(
        simd: V3,
        frame: &Frame<'_>,
        h: H,
        offsets: &[u32],
        base: usize,
        joints: &[u32],
        weights: &[f32],
        rest: &[Vec3],
        out: &mut [Vec3],
    ) -> usize {
        let zero = simd.avx._mm256_setzero_ps();
        let mut done = 0;
        for ((offs, r), o) in offsets
            .chunks_exact(8)
            .zip(offsets.get(1..).unwrap_or_default().chunks_exact(8))
            .zip(rest.chunks_exact(8))
            .zip(out.chunks_exact_mut(8))
            .map(|(((a, b), r), o)| ((a.iter().zip(b), r), o))
        {
            let (Ok(r), Ok(o)) = (<&[Vec3; 8]>::try_from(r), <&mut [Vec3; 8]>::try_from(o)) else {
                break;
            };
            let mut dq = [zero; 8];
            let mut sc = [zero; 8];
            for (l, (&a, &b)) in offs.enumerate() {
                let range = a as usize - base..b as usize - base;
                let (Some(j), Some(w)) = (joints.get(range.clone()), weights.get(range)) else {
                    continue;
                };
                [dq[l], sc[l]] = dq_blend::<SCALE, H>(simd, frame, h, j, w);
            }
            dq_apply8::<SCALE>(simd, dq, sc, r, o);
            done += 8;
        }
        done
    }
}

/// DQS of the leading blocks of eight vertices of a fixed-width chunk, as
/// `dqs::skin_fixed_with` (pivot in slot 0 of each vertex's `W` slots, the point scaled by
/// the blended scale/shear when `SCALE`). Returns how many vertices it skinned (a multiple
/// of 8; 0 without AVX2 + FMA); the caller skins the rest.
#[inline]
pub(crate) fn dqs_fixed<const W: usize, const SCALE: bool, H: Hemisphere>(
    frame: &Frame<'_>,
    h: H,
    joints: &[u32],
    weights: &[f32],
    rest: &[Vec3],
    out: &mut [Vec3],
) -> usize {
    #[cfg(target_arch = "x86_64")]
    if let Some(simd) = x86::V3::try_new().filter(|_| enabled()) {
        return simd.vectorize(
            #[inline(always)]
            || x86::dqs_fixed::<W, SCALE, H>(simd, frame, h, joints, weights, rest, out),
        );
    }
    let _ = (frame, h, joints, weights, rest, out);
    0
}

/// DQS of the leading blocks of eight vertices of a sparse (CSR) chunk, as
/// `dqs::skin_sparse` (`offsets` has one more entry than `rest` and indexes the full
/// arrays, of which `joints`/`weights` start at `base`; each row's pivot first; the point
/// scaled by the blended scale/shear when the frame has joint scale). Returns how many
/// vertices it skinned (a multiple of 8; 0 without AVX2 + FMA); the caller skins the rest.
#[inline]
#[allow(clippy::too_many_arguments)]
pub(crate) fn dqs_sparse<H: Hemisphere>(
    frame: &Frame<'_>,
    h: H,
    offsets: &[u32],
    base: usize,
    joints: &[u32],
    weights: &[f32],
    rest: &[Vec3],
    out: &mut [Vec3],
) -> usize {
    #[cfg(target_arch = "x86_64")]
    if let Some(simd) = x86::V3::try_new().filter(|_| enabled()) {
        return simd.vectorize(
            #[inline(always)]
            || {
                if frame.has_scale {
                    x86::dqs_sparse::<true, H>(
                        simd, frame, h, offsets, base, joints, weights, rest, out,
                    )
                } else {
                    x86::dqs_sparse::<false, H>(
                        simd, frame, h, offsets, base, joints, weights, rest, out,
                    )
                }
            },
        );
    }
    let _ = (frame, h, offsets, base, joints, weights, rest, out);
    0
}

#[cfg(test)]
mod tests {
    use super::PORTABLE_ONLY;
    use crate::skinning::{skin_frames, PackedInfluences};
    use glam::{Mat4, Quat, Vec3};
    use rigport_model::SkinningMethod;
    use rigport_model::{Influence, Influences};

    /// A tiny seeded generator (xorshift64*).
    struct Rng(u64);
    impl Rng {
        fn unit(&mut self) -> f32 {
            self.0 ^= self.0 >> 12;
            self.0 ^= self.0 << 25;
            self.0 ^= self.0 >> 27;
            (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 40) as f32 / (1u64 << 24) as f32
        }
        fn range(&mut self, lo: f32, hi: f32) -> f32 {
            lo + (hi - lo) * self.unit()
        }
    }

    fn skin(
        method: SkinningMethod,
        portable: bool,
        p: &PackedInfluences,
        rest: &[Vec3],
        mats: &[Mat4],
    ) -> Vec<Vec3> {
        PORTABLE_ONLY.with(|c| c.set(portable));
        let mut out = vec![Vec3::ZERO; rest.len() * (mats.len() / 16)];
        skin_frames(method, p, rest, mats, &mut out).unwrap();
        PORTABLE_ONLY.with(|c| c.set(false));
        out
    }

    /// The kernels agree with the portable loops for every fixed width, the sparse layout,
    /// DQS with and without joint scale, and palettes with joints in both hemispheres (so
    /// the sign table is used), over vertex counts that leave a tail after the 8-blocks.
    #[test]
    fn kernels_match_the_portable_loops() {
        let mut rng = Rng(0x5EED_0000_0000_0517);
        for per_vertex in [1usize, 2, 3, 4, 5, 8, 11] {
            for scale in [0.0f32, 0.2] {
                let v = 8 * 13 + 5;
                let rest: Vec<Vec3> = (0..v)
                    .map(|_| {
                        Vec3::new(
                            rng.range(-1.0, 1.0),
                            rng.range(0.0, 2.0),
                            rng.range(-1.0, 1.0),
                        )
                    })
                    .collect();
                let infl = Influences::from_rows((0..v).map(|i| {
                    let n = 1 + (i % per_vertex);
                    (0..n)
                        .map(|_| Influence {
                            joint: (rng.unit() * 16.0) as u32 % 16,
                            weight: rng.range(0.05, 1.0),
                        })
                        .collect::<Vec<_>>()
                }));
                let mats: Vec<Mat4> = (0..32)
                    .map(|_| {
                        let axis =
                            Vec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), 0.5).normalize();
                        let s = Vec3::new(1.0 + scale * rng.unit(), 1.0, 1.0 - scale * rng.unit());
                        let t = Vec3::new(
                            rng.range(-1.0, 1.0),
                            rng.range(-1.0, 1.0),
                            rng.range(-1.0, 1.0),
                        );
                        Mat4::from_scale_rotation_translation(
                            s,
                            Quat::from_axis_angle(axis, rng.range(-3.0, 3.0)),
                            t,
                        )
                    })
                    .collect();
                let packed = PackedInfluences::new(&infl);
                for method in [SkinningMethod::Lbs, SkinningMethod::Dqs] {
                    let fast = skin(method, false, &packed, &rest, &mats);
                    let portable = skin(method, true, &packed, &rest, &mats);
                    for (i, (a, b)) in fast.iter().zip(&portable).enumerate() {
                        assert!(
                            a.abs_diff_eq(*b, 2e-5),
                            "{method:?}, {per_vertex} per vertex, scale {scale}, output {i}: {a} vs {b}"
                        );
                    }
                }
            }
        }
    }
}
