//! Why a clip has no contacts: no foot ever slows under the contact speed, and whether the
//! feet's speeds say the clip plays at the wrong frame rate.

use super::FootlockOptions;

/// The height of the human a skeleton is taken to be when its speeds are judged in metres
/// per second (an adult: 1.6-1.8 m; the skeleton height is the joints' extent, a little
/// under the body's).
pub const HUMAN_HEIGHT_M: f32 = 1.7;

/// The fastest a human foot plausibly moves for most of a clip: the median speed of the
/// slowest foot joint, metres per second. A walk's feet are planted for about 60% of the
/// time, so its median sits near 0.3 m/s; a sprint's swing at up to 10 m/s but are planted
/// for a third of the time. On the corpus (taking each skeleton as 1.7 m) the medians are
/// 0.2-0.6 m/s for walks and dances, 3.1 m/s for CMU's run and 3.8 m/s for Bandai's dash;
/// the run played at twice its rate reaches 6.3 m/s.
pub const MAX_MEDIAN_FOOT_SPEED: f32 = 5.0;

/// The frame rates motion capture is recorded at, for a suggestion.
pub const COMMON_FPS: [f32; 9] = [24.0, 25.0, 30.0, 48.0, 50.0, 60.0, 100.0, 120.0, 240.0];

/// Speeds of one foot joint (skeleton heights per second) over the clip.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FootSpeeds {
    /// The slowest the joint stays over the shortest contact while low enough for one: the
    /// least, over every run of that many frames low enough, of the run's fastest frame
    /// (infinite when there is no such run).
    pub slowest_low: f32,
    /// The median frame.
    pub median: f32,
}

impl FootSpeeds {
    /// From the speed at each frame, whether the joint is low enough for a contact there,
    /// and the shortest contact in frames.
    pub fn of(speeds: &[f32], low: &[bool], min_frames: usize) -> Self {
        let n = min_frames.max(1);
        let slowest_low = speeds
            .windows(n)
            .zip(low.windows(n))
            .filter(|(_, low)| low.iter().all(|l| *l))
            .map(|(v, _)| v.iter().copied().fold(0.0, f32::max))
            .fold(f32::INFINITY, f32::min);
        let mut sorted: Vec<f32> = speeds.iter().copied().filter(|v| v.is_finite()).collect();
        sorted.sort_by(f32::total_cmp);
        Self {
            slowest_low,
            median: sorted.get(sorted.len() / 2).copied().unwrap_or(0.0),
        }
    }
}

/// Why no contact was found (see [`no_contact_cause`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cause {
    /// The slowest any foot joint stays over the shortest contact while low (heights per
    /// second, above the contact speed).
    pub slowest: f32,
    /// The median speed of the slowest foot joint, metres per second for a human of
    /// [`HUMAN_HEIGHT_M`].
    pub median_m_s: f32,
    /// When that median is above [`MAX_MEDIAN_FOOT_SPEED`]: the factor by which the clip
    /// seems to play too fast, and the common frame rate it was likely recorded at.
    pub rate: Option<(f32, f32)>,
}

/// Why no contact was found, from every foot joint's speeds (heights per second) at the
/// clip's rate `fps`: `None` when some joint does stay under the contact speed while low
/// (then hysteresis or the contact's length lost it); otherwise the [`Cause`].
pub fn no_contact_cause(
    joints: &[FootSpeeds],
    fps: f32,
    options: &FootlockOptions,
) -> Option<Cause> {
    let slowest = joints
        .iter()
        .map(|s| s.slowest_low)
        .fold(f32::INFINITY, f32::min);
    if slowest <= options.speed {
        return None;
    }
    let median = joints
        .iter()
        .map(|s| s.median)
        .fold(f32::INFINITY, f32::min);
    let median_m_s = median * HUMAN_HEIGHT_M;
    let rate = (median_m_s > MAX_MEDIAN_FOOT_SPEED && fps > 0.0).then(|| {
        // The slow-down that brings the median to a plausible speed, and the common rate
        // at or below the stated rate divided by it. (The slowest foot's speed over the
        // contact speed is a poorer guide: a wrong rate also blurs the stance, so on the
        // corpus run played 4x too fast it says 6x.)
        let factor = (median_m_s / MAX_MEDIAN_FOOT_SPEED).min(1e6);
        let suggested = COMMON_FPS
            .iter()
            .rev()
            .copied()
            .find(|&r| r <= fps / factor)
            .unwrap_or(fps / factor);
        (fps / suggested, suggested)
    });
    Some(Cause {
        slowest,
        median_m_s,
        rate,
    })
}
