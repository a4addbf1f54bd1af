//! Packing sparse per-vertex influences into glTF's fixed `JOINTS_n` / `WEIGHTS_n` sets.
//!
//! Rules (glTF 2.0 §3.7.3.3 "Skinned Mesh Attributes", and what Khronos glTF-Validator
//! checks in `validate_accessors.dart`):
//! 1. entries naming the same palette joint are merged (their weights added);
//! 2. weights below [`WEIGHT_EPSILON`] times the row's total (zero included) are dropped
//!    silently: they are arithmetic noise, not authored data;
//! 3. the rest is sorted by weight, largest first, ties by palette index (deterministic);
//! 4. the `max_influences` largest are kept, the rest dropped and reported;
//! 5. the kept weights are renormalized in `f64`, rounded to `f32`, and then adjusted so that
//!    their sum, computed **the way the validator computes it**, is exactly 1 (see
//!    [`validator_sum`]);
//! 6. unused slots get joint 0 and weight 0 (the validator warns about a non-zero joint
//!    with zero weight);
//! 7. a vertex left with no influence is bound with weight 1 to a fallback palette joint
//!    chosen by the caller, and reported.
//!
//! Merging comes before the epsilon test so that a weight split into several tiny entries
//! for one joint is kept when its total is not negligible.

use rigport_model::conventions::WEIGHT_EPSILON;
use rigport_model::{Influence, Influences};

use crate::labels::ROW_SUM_TOLERANCE;

/// Slots per vertex: two glTF sets (`JOINTS_0`/`WEIGHTS_0`, `JOINTS_1`/`WEIGHTS_1`) of four.
pub(crate) const MAX_SLOTS: usize = 8;

/// Slots per glTF set (`VEC4`).
pub(crate) const SET_SLOTS: usize = 4;

/// The order in which glTF-Validator adds a vertex's weights: it steps all sets one
/// component at a time, so with two sets it reads `W0.x, W1.x, W0.y, W1.y, ...`
/// (`InfluencesChecker.checkNext`). Slot `s` is set `s / 4`, component `s % 4`.
const VALIDATOR_ORDER: [usize; MAX_SLOTS] = [0, 4, 1, 5, 2, 6, 3, 7];

/// How many steps each way around the residual-corrected weight [`fix_sum`] tries.
const SEARCH_STEPS: i32 = 8;

/// One vertex's packed influences: slots `0..4` are set 0, `4..8` set 1.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct PackedRow {
    /// Palette indices; 0 in unused slots.
    pub joints: [u16; MAX_SLOTS],
    /// Weights, non-increasing over the used slots, 0 in unused slots.
    pub weights: [f32; MAX_SLOTS],
}

/// What packing one row did, for the warnings.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct RowReport {
    /// The largest weight dropped to the limit, as a fraction of the row's total, if any.
    pub dropped: Option<f32>,
    /// The row had no influence left and was bound to the fallback joint.
    pub unbound: bool,
    /// `|sum - 1|` of the input row (after merging and dropping tiny weights).
    pub sum_error: f64,
}

/// Per-mesh totals of [`RowReport`]s.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct PackStats {
    /// Vertices that lost weight to the limit.
    pub limited_vertices: usize,
    /// The largest single weight dropped to the limit (fraction of its row's total).
    pub max_dropped_weight: f32,
    /// Vertices bound to the fallback joint.
    pub unbound_vertices: usize,
    /// Rows whose input sum was off by more than [`ROW_SUM_TOLERANCE`].
    pub renormalized_rows: usize,
    /// The largest input `|sum - 1|` among those rows.
    pub max_row_sum_error: f32,
}

/// Every vertex of a skin, packed.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct Packed {
    /// One row per vertex.
    pub rows: Vec<PackedRow>,
    /// What was dropped or repaired.
    pub stats: PackStats,
}

impl Packed {
    /// Whether any vertex uses a slot of set 1 (then `JOINTS_1`/`WEIGHTS_1` are written).
    pub(crate) fn uses_second_set(&self) -> bool {
        self.rows.iter().any(|r| r.weights[SET_SLOTS] != 0.0)
    }
}

/// Packs every vertex of `influences`.
///
/// `max_influences` is the number of slots kept (`1..=8`); `fallback` the palette index
/// given weight 1 on vertices without influence. Palette indices must fit in `u16` (the
/// caller checks the palette size).
pub(crate) fn pack(influences: &Influences, max_influences: usize, fallback: u16) -> Packed {
    let mut scratch = Vec::new();
    let mut out = Packed {
        rows: Vec::with_capacity(influences.vertex_count()),
        stats: PackStats::default(),
    };
    for row in influences.rows() {
        let (packed, report) = pack_row(row, max_influences, fallback, &mut scratch);
        out.rows.push(packed);
        let s = &mut out.stats;
        if let Some(w) = report.dropped {
            s.limited_vertices += 1;
            s.max_dropped_weight = s.max_dropped_weight.max(w);
        }
        if report.unbound {
            s.unbound_vertices += 1;
        }
        if report.sum_error > ROW_SUM_TOLERANCE {
            s.renormalized_rows += 1;
            s.max_row_sum_error = s.max_row_sum_error.max(report.sum_error as f32);
        }
    }
    out
}

/// Packs one vertex's influences; see the module docs for the rules.
///
/// `scratch` is reused between calls to avoid an allocation per vertex.
pub(crate) fn pack_row(
    row: &[Influence],
    max_influences: usize,
    fallback: u16,
    scratch: &mut Vec<(u32, f64)>,
) -> (PackedRow, RowReport) {
    let max_influences = max_influences.clamp(1, MAX_SLOTS);
    let mut report = RowReport::default();
    let mut packed = PackedRow {
        joints: [0; MAX_SLOTS],
        weights: [0.0; MAX_SLOTS],
    };

    // 1. Merge duplicates (sort by joint, add neighbours) in f64.
    scratch.clear();
    scratch.extend(
        row.iter()
            // Negative and non-finite weights are rejected by Asset::validate; treat them as
            // absent rather than trusting that here.
            .filter(|i| i.weight.is_finite() && i.weight > 0.0)
            .map(|i| (i.joint, f64::from(i.weight))),
    );
    // Fast path: with small palette indices a bit set proves there is nothing to merge,
    // which is the usual case and saves a sort per vertex.
    let mut seen = 0_u64;
    let needs_merge = scratch.iter().any(|&(j, _)| {
        let bit = 1_u64.checked_shl(j).unwrap_or(0);
        let repeat = bit == 0 || seen & bit != 0;
        seen |= bit;
        repeat
    });
    if needs_merge {
        scratch.sort_by_key(|&(j, _)| j);
        let mut merged = 0;
        for k in 0..scratch.len() {
            if merged > 0 && scratch[merged - 1].0 == scratch[k].0 {
                scratch[merged - 1].1 += scratch[k].1;
            } else {
                scratch[merged] = scratch[k];
                merged += 1;
            }
        }
        scratch.truncate(merged);
    }
    // 2. Drop negligible weights, relative to the row's total so that unnormalized rows
    //    (sums of 100, say) are judged like normalized ones.
    let merged_total: f64 = scratch.iter().map(|&(_, w)| w).sum();
    scratch.retain(|&(_, w)| w / merged_total >= f64::from(WEIGHT_EPSILON));
    // 3. Largest first, ties by palette index.
    //    Importers usually hand rows over in this order already.
    if !scratch.is_sorted_by(|a, b| a.1 > b.1 || (a.1 == b.1 && a.0 < b.0)) {
        scratch.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
    }

    if scratch.is_empty() {
        report.unbound = true;
        packed.joints[0] = fallback;
        packed.weights[0] = 1.0;
        return (packed, report);
    }
    let total: f64 = scratch.iter().map(|&(_, w)| w).sum();
    report.sum_error = (total - 1.0).abs();

    // 4. Keep the largest; the first dropped entry is the largest dropped.
    if scratch.len() > max_influences {
        report.dropped = Some((scratch[max_influences].1 / total) as f32);
        scratch.truncate(max_influences);
    }

    // A row that already sums to exactly 1 the validator's way is kept bit for bit (this
    // makes packing idempotent and leaves clean data alone).
    let mut n = 0;
    for &(j, w) in scratch.iter() {
        packed.joints[n] = j as u16;
        packed.weights[n] = w as f32;
        n += 1;
    }
    if report.dropped.is_none()
        && scratch.iter().all(|&(_, w)| f64::from(w as f32) == w)
        && validator_sum(&packed.weights) == 1.0
    {
        return (packed, report);
    }

    // 5. Renormalize, round to f32, and fix the validator's sum.
    let kept: f64 = scratch.iter().map(|&(_, w)| w).sum();
    packed.joints = [0; MAX_SLOTS];
    packed.weights = [0.0; MAX_SLOTS];
    n = 0;
    for &(j, w) in scratch.iter() {
        let w = (w / kept) as f32;
        // A weight can only round to zero for absurdly unnormalized input (a 1e-6 weight
        // beside a 1e40 one); a zero weight must not keep a joint index.
        if w > 0.0 {
            packed.joints[n] = j as u16;
            packed.weights[n] = w;
            n += 1;
        }
    }
    // Rounding to f32 can make neighbours equal: restore the tie order by palette index.
    sort_row(&mut packed, n);
    fix_sum(&mut packed, n);
    (packed, report)
}

/// Sorts the first `n` slots by weight (descending), ties by palette index (ascending).
fn sort_row(row: &mut PackedRow, n: usize) {
    let mut pairs: [(u16, f32); MAX_SLOTS] = [(0, 0.0); MAX_SLOTS];
    for (k, p) in pairs.iter_mut().enumerate().take(n) {
        *p = (row.joints[k], row.weights[k]);
    }
    pairs[..n].sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
    for (k, &(j, w)) in pairs.iter().enumerate().take(n) {
        row.joints[k] = j;
        row.weights[k] = w;
    }
}

/// The weight sum exactly as glTF-Validator computes it: in [`VALIDATOR_ORDER`], each
/// partial sum rounded to `f32` (`_sum = doubleToSingle(_sum + weight)`; the `f64` add of
/// two `f32`s rounded to `f32` equals the `f32` add, since 53 ≥ 2·24 + 2).
pub(crate) fn validator_sum(weights: &[f32; MAX_SLOTS]) -> f32 {
    VALIDATOR_ORDER
        .iter()
        .map(|&s| weights[s])
        .filter(|&w| w != 0.0)
        .fold(0.0_f32, |sum, w| sum + w)
}

/// Whether the first `n` slots are positive and in canonical order (weight descending, ties
/// by palette index).
fn is_canonical(row: &PackedRow, n: usize) -> bool {
    row.weights[..n].iter().all(|&w| w > 0.0)
        && (1..n).all(|k| {
            let (wa, wb) = (row.weights[k - 1], row.weights[k]);
            wa > wb || (wa == wb && row.joints[k - 1] < row.joints[k])
        })
}

/// Adjusts one weight so that [`validator_sum`] is exactly 1.
///
/// The validator accepts `|sum − 1| ≤ 2e-7 · n` (gltf-validator 2.0.0-dev.3.10) or, in
/// later sources, `≤ 0.0039216 · (⌈n/2⌉ − 1)`, i.e. *exactly* 1 for one or two weights; an
/// exact 1 satisfies every version.
///
/// Each weight in turn (largest first) absorbs the residual, `wᵢ += 1 − sum`, and nearby
/// values are tried: steps of 2⁻²⁶ (a quarter of the sum's ulp just below 1) and of the
/// weight's own ulp. Adjusting the largest weight alone is not always enough: when a
/// smaller weight has bits below the partial sum's ulp, round-half-even makes the partial
/// sum move in steps of two ulps and skip 1; a smaller weight, with a finer grid, can land
/// it. Candidates must keep the canonical order. If no exact candidate exists (not
/// observed), the closest sum found is kept.
fn fix_sum(row: &mut PackedRow, n: usize) {
    let sum = validator_sum(&row.weights);
    if sum == 1.0 {
        return;
    }
    let residual = 1.0 - f64::from(sum);
    let mut best = (f64::from(sum) - 1.0).abs();
    let mut best_row = *row;
    let quarter_ulp = f64::from(f32::EPSILON) / 8.0; // 2⁻²⁶
    for i in 0..n {
        let start = f64::from(row.weights[i]) + residual;
        let fine = (-SEARCH_STEPS..=SEARCH_STEPS)
            .map(|k| Some((start + f64::from(k) * quarter_ulp) as f32));
        let ulps = (-SEARCH_STEPS..=SEARCH_STEPS).map(|k| step_ulps(start as f32, k));
        for candidate in fine.chain(ulps).flatten() {
            let mut trial = *row;
            trial.weights[i] = candidate;
            if !is_canonical(&trial, n) {
                continue;
            }
            let s = validator_sum(&trial.weights);
            if s == 1.0 {
                *row = trial;
                return;
            }
            let err = (f64::from(s) - 1.0).abs();
            if err < best {
                best = err;
                best_row = trial;
            }
        }
    }
    *row = best_row;
}

/// `x` moved by `k` ulps (positive `x` only); `None` when that leaves the positive finite
/// range.
fn step_ulps(x: f32, k: i32) -> Option<f32> {
    if !(x > 0.0 && x.is_finite()) {
        return None;
    }
    let bits = i64::from(x.to_bits()) + i64::from(k);
    let y = f32::from_bits(u32::try_from(bits).ok()?);
    (y > 0.0 && y.is_finite()).then_some(y)
}

/// The influences of `skin` exactly as the glTF exporter writes them for a per-vertex
/// limit of `max_influences` (`1..=8`, clamped): merged, tiny weights dropped, the largest
/// kept and renormalized so that the f32 sum is 1, vertices without influence bound to the
/// skin's root palette joint. Lets an evaluator show what a glTF viewer of that file
/// computes.
pub fn gltf_influences(
    skeleton: &rigport_model::Skeleton,
    skin: &rigport_model::SkinBinding,
    max_influences: usize,
) -> Influences {
    let fallback = crate::labels::fallback_palette_index(skeleton, &skin.joints);
    let packed = pack(&skin.influences, max_influences, fallback as u16);
    Influences::from_rows(packed.rows.iter().map(|r| {
        r.joints
            .iter()
            .zip(r.weights)
            .filter(|(_, w)| *w > 0.0)
            .map(|(j, w)| Influence {
                joint: u32::from(*j),
                weight: w,
            })
            .collect::<Vec<_>>()
    }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn inf(joint: u32, weight: f32) -> Influence {
        Influence { joint, weight }
    }

    fn one(row: &[Influence], max: usize) -> (PackedRow, RowReport) {
        pack_row(row, max, 7, &mut Vec::new())
    }

    /// The validator's rule of gltf-validator 2.0.0-dev.3.10: `|sum − 1| ≤ 2e-7 · n`, the
    /// threshold accumulated in f64 per unique non-zero weight.
    fn validator_accepts(row: &PackedRow) -> bool {
        let n = row.weights.iter().filter(|&&w| w != 0.0).count();
        let threshold = (0..n).fold(0.0_f64, |t, _| t + 2e-7);
        (f64::from(validator_sum(&row.weights)) - 1.0).abs() <= threshold
    }

    #[test]
    fn merges_drops_tiny_and_sorts() {
        let (p, r) = one(
            &[
                inf(3, 0.2),
                inf(1, 0.3),
                inf(3, 0.2),
                inf(2, 1e-7),
                inf(5, 0.0),
                inf(4, 0.3),
            ],
            4,
        );
        assert_eq!(&p.joints[..4], &[3, 1, 4, 0]);
        assert_eq!(p.weights[3], 0.0);
        assert!((p.weights[0] - 0.4).abs() < 1e-6 && (p.weights[1] - 0.3).abs() < 1e-6);
        assert_eq!(p.weights[1], p.weights[2], "tie kept in palette order 1, 4");
        assert_eq!(validator_sum(&p.weights), 1.0);
        assert_eq!(r.dropped, None, "tiny weights are not reported as dropped");
        assert!(!r.unbound);
    }

    #[test]
    fn limit_reports_largest_dropped_fraction() {
        let row: Vec<_> = (0..6).map(|j| inf(j, (6 - j) as f32)).collect(); // 6,5,4,3,2,1
        let (p, r) = one(&row, 4);
        assert_eq!(&p.joints[..4], &[0, 1, 2, 3]);
        assert_eq!(r.dropped, Some(2.0 / 21.0));
        assert!((p.weights[0] - 6.0 / 18.0).abs() < 1e-6);
        assert_eq!(validator_sum(&p.weights), 1.0);
        assert!((r.sum_error - 20.0).abs() < 1e-9);
    }

    #[test]
    fn empty_rows_bind_to_the_fallback() {
        for row in [vec![], vec![inf(2, 0.0)], vec![inf(2, 0.0), inf(3, -0.0)]] {
            let (p, r) = one(&row, 4);
            assert!(r.unbound);
            assert_eq!(p.joints, [7, 0, 0, 0, 0, 0, 0, 0]);
            assert_eq!(p.weights, [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]);
        }
        // Tiny is relative to the row: a lone small weight is the whole row.
        let (p, r) = one(&[inf(2, 6e-7)], 4);
        assert!(!r.unbound);
        assert_eq!((p.joints[0], p.weights[0]), (2, 1.0));
        // One tiny weight is dropped; split tiny weights for one joint merge above it.
        let (p, _) = one(&[inf(1, 1.0), inf(2, 6e-7)], 4);
        assert_eq!(p.joints[..2], [1, 0]);
        assert_eq!(p.weights[..2], [1.0, 0.0]);
        let (p, _) = one(&[inf(1, 1.0), inf(2, 6e-7), inf(2, 6e-7)], 4);
        assert_eq!(p.joints[..2], [1, 2]);
    }

    #[test]
    fn thirds_sum_exactly_to_one() {
        // 3 × f32(1/3) sums to 1 + 2⁻²³ sequentially: one weight must give an ulp, and
        // the tie order must survive.
        let (p, _) = one(&[inf(0, 1.0), inf(1, 1.0), inf(2, 1.0)], 4);
        assert_eq!(validator_sum(&p.weights), 1.0);
        assert!(is_canonical(&p, 3), "{p:?}");
    }

    #[test]
    fn eight_slots_use_the_interleaved_validator_order() {
        let row: Vec<_> = (0..8).map(|j| inf(j, 1.0 + j as f32 * 0.37)).collect();
        let (p, _) = one(&row, 8);
        assert_eq!(&p.joints, &[7, 6, 5, 4, 3, 2, 1, 0]);
        assert_eq!(validator_sum(&p.weights), 1.0);
        let packed = pack(&Influences::from_rows([row]), 8, 0);
        assert!(packed.uses_second_set());
    }

    #[test]
    fn pack_collects_stats() {
        let rows = vec![
            vec![
                inf(0, 0.5),
                inf(1, 0.25),
                inf(2, 0.125),
                inf(3, 0.0625),
                inf(4, 0.0625),
            ],
            vec![],
            vec![inf(1, 0.9996)],
            vec![inf(0, 0.6), inf(1, 0.4)],
        ];
        let packed = pack(&Influences::from_rows(rows), 4, 3);
        assert_eq!(packed.rows.len(), 4);
        assert!(!packed.uses_second_set());
        let s = packed.stats;
        assert_eq!(s.limited_vertices, 1);
        assert_eq!(s.max_dropped_weight, 0.0625);
        assert_eq!(s.unbound_vertices, 1);
        assert_eq!(s.renormalized_rows, 1);
        assert!((s.max_row_sum_error - 0.0004).abs() < 1e-6);
        assert_eq!(packed.rows[1].joints[0], 3);
    }

    /// A row of raw influences: joints 0..12 (duplicates likely), weights from several
    /// regimes (normalized, tiny, zero, large, unnormalized).
    fn raw_row() -> impl Strategy<Value = Vec<Influence>> {
        let weight = prop_oneof![
            4 => 0.0_f32..1.0,
            1 => Just(0.0_f32),
            1 => 0.0_f32..2e-6,
            1 => 0.0_f32..1000.0,
            1 => (1_u32..8).prop_map(|k| 1.0 / k as f32),
        ];
        prop::collection::vec((0_u32..12, weight), 0..16).prop_map(|v| {
            v.into_iter()
                .map(|(joint, weight)| inf(joint, weight))
                .collect()
        })
    }

    /// The reference: merged, non-tiny entries, canonical order (in f64).
    fn reference(row: &[Influence]) -> Vec<(u32, f64)> {
        let mut m: std::collections::BTreeMap<u32, f64> = Default::default();
        for i in row {
            *m.entry(i.joint).or_default() += f64::from(i.weight);
        }
        let total: f64 = m.values().sum();
        let mut v: Vec<_> = m
            .into_iter()
            .filter(|&(_, w)| w / total >= f64::from(WEIGHT_EPSILON))
            .collect();
        v.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
        v
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(4096))]

        #[test]
        fn packed_rows_follow_the_rules(row in raw_row(), max in 1_usize..=8) {
            let (p, r) = pack_row(&row, max, 11, &mut Vec::new());
            let n = p.weights.iter().filter(|&&w| w != 0.0).count();
            // Validator-exact sum: the 2e-7·n rule, and in fact exactly 1.
            prop_assert!(validator_accepts(&p), "{p:?}");
            prop_assert_eq!(validator_sum(&p.weights), 1.0, "{:?}", p);
            // At most N kept, used slots first, canonical order, zero slots use joint 0.
            prop_assert!(n <= max && n >= 1);
            prop_assert!(is_canonical(&p, n), "{:?}", p);
            for s in n..MAX_SLOTS {
                prop_assert_eq!((p.joints[s], p.weights[s]), (0, 0.0));
            }
            // No joint twice among the used slots.
            let mut used: Vec<u16> = p.joints[..n].to_vec();
            used.sort_unstable();
            used.dedup();
            prop_assert_eq!(used.len(), n);

            let reference = reference(&row);
            if reference.is_empty() {
                prop_assert!(r.unbound);
                prop_assert_eq!((p.joints[0], p.weights[0]), (11, 1.0));
                return Ok(());
            }
            prop_assert!(!r.unbound);
            // The kept joints are the N largest; weights proportional to the input.
            let keep = reference.len().min(max);
            let kept_total: f64 = reference[..keep].iter().map(|&(_, w)| w).sum();
            let mut expect_joints: Vec<u16> =
                reference[..keep].iter().map(|&(j, _)| j as u16).collect();
            expect_joints.sort_unstable();
            prop_assert_eq!(&used, &expect_joints);
            for s in 0..n {
                let (_, w) = reference
                    .iter()
                    .find(|&&(j, _)| j as u16 == p.joints[s])
                    .copied()
                    .unwrap_or_default();
                prop_assert!((f64::from(p.weights[s]) - w / kept_total).abs() < 1e-6);
            }
            // Dropping is reported exactly when the limit bit, with the largest dropped.
            if reference.len() > max {
                let total: f64 = reference.iter().map(|&(_, w)| w).sum();
                prop_assert_eq!(r.dropped, Some((reference[max].1 / total) as f32));
            } else {
                prop_assert_eq!(r.dropped, None);
            }
        }

        #[test]
        fn packing_is_idempotent(row in raw_row(), max in 1_usize..=8) {
            let (p, _) = pack_row(&row, max, 0, &mut Vec::new());
            let again: Vec<Influence> = (0..MAX_SLOTS)
                .filter(|&s| p.weights[s] != 0.0)
                .map(|s| inf(u32::from(p.joints[s]), p.weights[s]))
                .collect();
            let (q, r) = pack_row(&again, max, 0, &mut Vec::new());
            prop_assert_eq!(p, q);
            prop_assert_eq!(r.dropped, None);
        }
    }
}
