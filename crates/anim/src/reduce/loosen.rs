//! Step 4: spending the budget the first pass left unused. The split of step 1 is
//! conservative where a subtree's errors do not line up (most joints end far below the
//! bound); each round scales up the local tolerance of every channel whose subtree stays
//! under the bound by the slack it has, re-simplifies and verifies. Where a joint then
//! fails, the channels above it that changed go back to their last verified keys and stay
//! there: a joint's error depends only on the channels on its path, so the bound holds
//! again.

use super::{ReduceError, Reducer};

/// Rounds of loosening at most (a round that saves under 1% of the keys is the last).
const ROUNDS: usize = 6;
/// A subtree loosens when its largest error is below this fraction of the bound.
const SLACK: f32 = 0.8;
/// The largest factor one round scales a tolerance by.
const MAX_FACTOR: f32 = 3.0;

impl Reducer<'_> {
    /// Loosens from the verified state whose per-joint errors are `errors`. Returns the
    /// final largest and mean error.
    pub(super) fn loosen(
        &mut self,
        (mut errors, mut mean): (Vec<f32>, f32),
    ) -> Result<(f32, f32), ReduceError> {
        let tol = self.tolerance;
        let n = self.parents.len();
        let mut frozen = vec![false; self.channels.len()];
        let kept = |r: &Self| -> usize {
            r.channels
                .iter()
                .map(|c| c.kept.as_ref().map_or(c.original.times.len(), Vec::len))
                .sum()
        };
        for _ in 0..ROUNDS {
            if tol <= 0.0 {
                break;
            }
            let before = kept(self);
            // The largest error in each joint's subtree (parents come first).
            let mut sub = errors.clone();
            for j in (0..n).rev() {
                if let Some(p) = self.parents[j] {
                    sub[p.get()] = sub[p.get()].max(sub[j]);
                }
            }
            let mut saved = Vec::new();
            let mut dirty = vec![false; self.channels.len()];
            for (ci, chan) in self.channels.iter_mut().enumerate() {
                let worst = sub.get(chan.joint).copied().unwrap_or(tol);
                if frozen[ci]
                    || chan.kept.is_none()
                    || !chan.eps.is_finite()
                    || worst >= SLACK * tol
                {
                    continue;
                }
                let factor = if worst > 0.0 {
                    (0.95 * tol / worst).min(MAX_FACTOR)
                } else {
                    MAX_FACTOR
                };
                saved.push((
                    ci,
                    chan.eps,
                    chan.kept.clone(),
                    chan.reduced.clone(),
                    chan.joint,
                    chan.fitted.clone(),
                ));
                chan.eps *= factor;
                dirty[ci] = true;
            }
            if saved.is_empty() {
                break;
            }
            self.simplify_dirty(&mut dirty);
            loop {
                let (now, now_mean) = self.errors()?;
                let failing: Vec<usize> = (0..n).filter(|&d| now[d] > tol).collect();
                if failing.is_empty() {
                    (errors, mean) = (now, now_mean);
                    break;
                }
                // Every changed channel on the path of a failing joint goes back.
                let mut reverted = false;
                for &d in &failing {
                    let mut cur = Some(d);
                    while let Some(a) = cur {
                        for entry in saved.iter_mut().filter(|e| e.4 == a) {
                            let chan = &mut self.channels[entry.0];
                            if frozen[entry.0] {
                                continue;
                            }
                            chan.eps = entry.1;
                            chan.kept = entry.2.take();
                            chan.reduced = entry.3.take();
                            chan.fitted = entry.5.take();
                            frozen[entry.0] = true;
                            reverted = true;
                        }
                        cur = self.parents[a].map(|p| p.get());
                    }
                }
                if !reverted {
                    // Not reachable (a failing joint has a changed channel above it):
                    // every change of the round goes back.
                    for entry in &mut saved {
                        if !frozen[entry.0] {
                            let chan = &mut self.channels[entry.0];
                            chan.eps = entry.1;
                            chan.kept = entry.2.take();
                            chan.reduced = entry.3.take();
                            chan.fitted = entry.5.take();
                            frozen[entry.0] = true;
                        }
                    }
                }
            }
            // A round that saved under 1% of the keys is the last.
            if kept(self) * 100 > before * 99 {
                break;
            }
        }
        Ok((errors.iter().copied().fold(0.0, f32::max), mean))
    }
}
