//! Step 2 of the reduction: the keys one channel keeps for its local tolerance, as the
//! smaller of two representations (each within the tolerance at every original key):
//!
//! - **key removal** (Douglas–Peucker, then a greedy pass): the fewest keys, at times of
//!   their own (a glTF sampler then needs its own time accessor: 4 bytes per key, weighed
//!   as the codec says: [`super::Codec::key_time_bytes`]);
//! - **a uniform rate**: every `k`-th key (and the last), the largest `k` within the
//!   tolerance (1: every key); every channel with the same key times and the same `k` shares one time
//!   accessor (glTF 2.0 §3.11 lets samplers share inputs), so a key costs only its value.
//!
//! Both keep a subset of the original keys, so values stay bit for bit and no resampling
//! error is added at the kept keys.

use glam::{Vec3, Vec4};

use rigport_model::Track;

use super::channel::{Channel, Kind};
use super::cubic::fit_cubic;
use super::curve::{lerp3, Slerp};
use super::rate::{ladder, uniform_keys, uniform_len, MAX_STEP, TIME_ACCESSOR_JSON};

/// The keys `chan` keeps for its tolerance `chan.eps` (indices, increasing, first and last
/// always among them) and, when a CUBICSPLINE fit of them needs fewer bytes than LINEAR
/// keys (`chan.cubic`), that cubic track.
pub(super) fn simplify(chan: &Channel) -> (Vec<usize>, Option<Track>) {
    let (kept, bytes) = linear(chan);
    if chan.cubic {
        if let Some((fit, _)) = fit_cubic(chan, bytes) {
            return (fit.kept, Some(fit.track));
        }
    }
    (kept, None)
}

/// The LINEAR keys `chan` keeps and their bytes as written (a key's value, and its time
/// unless the keys are at a uniform rate, whose times channels share).
fn linear(chan: &Channel) -> (Vec<usize>, usize) {
    let n = chan.original.times.len();
    let value = chan.value_bytes;
    if n <= 2 {
        return ((0..n).collect(), n * value);
    }
    let curve = Curve::new(chan);
    let removed = remove_keys(&curve, n);
    let budget = removed.len() * (value + chan.time_bytes) + TIME_ACCESSOR_JSON;
    if !chan.decimate {
        return (removed, budget);
    }
    // A uniform rate needs more keys than key removal (which keeps the fewest it can), so
    // only steps up to key removal's mean spacing can pass, and only those down to where
    // the uniform keys cost as much as key removal's can win: that range is all that is
    // tried.
    let widest = ((n - 1) / (removed.len() - 1).max(1)).min(MAX_STEP);
    let step = (2..=widest)
        .rev()
        .filter(|&k| ladder(k))
        .take_while(|&step| uniform_len(n, step) * value <= budget)
        .find(|&step| fits_uniform(&curve, n, step))
        // Every key (step 1) shares its times with the other full-rate channels.
        .unwrap_or(1);
    if uniform_len(n, step) * value <= budget {
        (uniform_keys(n, step), uniform_len(n, step) * value)
    } else {
        (removed, budget)
    }
}

/// Whether every `step`-th key (and the last) reproduces every original key within the
/// limit.
fn fits_uniform(curve: &Curve, n: usize, step: usize) -> bool {
    uniform_keys(n, step)
        .windows(2)
        .all(|w| curve.fits(w[0], w[1]))
}

/// One channel's keys as the simplifier reads them.
struct Curve<'a> {
    times: &'a [f32],
    kind: Kind,
    quats: &'a [glam::Quat],
    vectors: Vec<Vec3>,
    /// The tolerance in the units compared: a chord `|q1 - q2| = 2 sin(θ/4)` for
    /// rotations (no asin per key), a distance otherwise.
    limit: f32,
}

impl<'a> Curve<'a> {
    fn new(chan: &'a Channel) -> Self {
        let limit = match chan.kind {
            Kind::Rotation => 2.0 * (chan.eps.min(std::f32::consts::TAU) / 4.0).sin(),
            Kind::Translation | Kind::Scale => chan.eps,
        };
        let vectors = match chan.kind {
            Kind::Rotation => Vec::new(),
            Kind::Translation | Kind::Scale => chan
                .original
                .values
                .chunks_exact(3)
                .map(Vec3::from_slice)
                .collect(),
        };
        Self {
            times: &chan.original.times,
            kind: chan.kind,
            quats: &chan.quats,
            vectors,
            limit,
        }
    }

    /// The worst original key strictly between keys a and b when interpolating from a to
    /// b: (key, error), (a, 0) when there is none. Same arithmetic as the sampler.
    fn worst(&self, a: usize, b: usize) -> (usize, f32) {
        let (ta, tb) = (self.times[a], self.times[b]);
        let mut worst = (a, 0.0f32);
        match self.kind {
            Kind::Rotation => {
                let seg = Slerp::new(self.quats[a], self.quats[b]);
                let inner = self.times[a + 1..b].iter().zip(&self.quats[a + 1..b]);
                for (k, (&t, &o)) in (a + 1..).zip(inner) {
                    let q = Vec4::from(seg.at((t - ta) / (tb - ta)));
                    let o = Vec4::from(o);
                    let e = (q - o).length().min((q + o).length());
                    if e > worst.1 {
                        worst = (k, e);
                    }
                }
            }
            Kind::Translation | Kind::Scale => {
                let (va, vb) = (self.vectors[a], self.vectors[b]);
                let inner = self.times[a + 1..b].iter().zip(&self.vectors[a + 1..b]);
                for (k, (&t, &v)) in (a + 1..).zip(inner) {
                    let e = lerp3(va, vb, (t - ta) / (tb - ta)).distance(v);
                    if e > worst.1 {
                        worst = (k, e);
                    }
                }
            }
        }
        worst
    }

    /// Whether interpolating from a to b reproduces every key between within the limit.
    fn fits(&self, a: usize, b: usize) -> bool {
        self.worst(a, b).1 <= self.limit
    }
}

/// Douglas–Peucker (first and last key kept; a key goes when the interpolation between
/// the kept keys around it is within the limit), then one greedy pass: Douglas–Peucker
/// splits at the worst key, which is not always a key the result needs (e.g. inside a run
/// of equal values), so every kept key whose two kept neighbours already reproduce all
/// original keys between them goes.
fn remove_keys(curve: &Curve, n: usize) -> Vec<usize> {
    let mut keep = vec![false; n];
    keep[0] = true;
    keep[n - 1] = true;
    let mut stack = vec![(0usize, n - 1)];
    while let Some((a, b)) = stack.pop() {
        let (k, e) = curve.worst(a, b);
        if e > curve.limit {
            keep[k] = true;
            stack.push((a, k));
            stack.push((k, b));
        }
    }
    let kept: Vec<usize> = (0..n).filter(|&k| keep[k]).collect();
    let mut anchor = 0usize;
    for w in kept.windows(2).skip(1) {
        let (k, next) = (w[0], w[1]);
        if curve.fits(anchor, next) {
            keep[k] = false;
        } else {
            anchor = k;
        }
    }
    (0..n).filter(|&k| keep[k]).collect()
}
