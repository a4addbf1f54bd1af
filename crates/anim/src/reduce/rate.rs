//! Uniform key rates: which steps the reducer tries (every `k`-th source key), the keys a
//! step keeps, and what a time accessor of its own costs, shared by key removal and the
//! CUBICSPLINE fits.

/// The largest decimation step tried: beyond it (a key every 64 source frames, about 2 Hz
/// for 120 Hz capture) key removal keeps as few keys for a moving channel.
pub(super) const MAX_STEP: usize = 64;

/// What a time accessor of its own costs besides its 4 bytes per key: its JSON (about 110
/// bytes with its `min` and `max`, as the glTF writer prints them). On short clips that is
/// worth several keys, and a uniform rate's times are shared.
pub(super) const TIME_ACCESSOR_JSON: usize = 110;

/// What a CUBICSPLINE sampler costs besides its data: `,"interpolation":"CUBICSPLINE"` in
/// its JSON (a LINEAR sampler leaves the default out).
pub(super) const CUBIC_SAMPLER_JSON: usize = 29;

/// The uniform steps tried: a ladder of about 1.5x (2, 3, 4, 6, 8, 12, ...), so that
/// channels land on the same steps and share their times more often.
pub(super) fn ladder(step: usize) -> bool {
    if step < 2 {
        return false;
    }
    // 2^k or 3 * 2^(k-1): the two top bits are all the bits.
    let shift = step.ilog2() - 1;
    let top = step >> shift;
    (top == 2 || top == 3) && step.trailing_zeros() >= shift
}

/// How many keys [`uniform_keys`] keeps.
pub(super) fn uniform_len(n: usize, step: usize) -> usize {
    (n - 1) / step.max(1) + 1 + usize::from((n - 1) % step.max(1) != 0)
}

/// Keys `0, step, 2 step, ...` and the last.
pub(super) fn uniform_keys(n: usize, step: usize) -> Vec<usize> {
    let mut keys: Vec<usize> = (0..n).step_by(step.max(1)).collect();
    if keys.last() != Some(&(n - 1)) {
        keys.push(n - 1);
    }
    keys
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_ladder_steps_by_about_one_and_a_half() {
        let steps: Vec<usize> = (0..=MAX_STEP).filter(|&k| ladder(k)).collect();
        assert_eq!(steps, [2, 3, 4, 6, 8, 12, 16, 24, 32, 48, 64]);
    }

    #[test]
    fn uniform_len_counts_uniform_keys() {
        for n in 2..40 {
            for step in 1..12 {
                assert_eq!(
                    uniform_len(n, step),
                    uniform_keys(n, step).len(),
                    "{n} {step}"
                );
            }
        }
    }
}
