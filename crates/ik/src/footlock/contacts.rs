//! Contact detection, pins and blend weights: plain functions over one joint's sampled
//! model-space positions.

use glam::Vec3;

/// Thresholds of [`detect`], already in the clip's units.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Thresholds {
    /// A contact starts below this height above the joint's lowest point (length unit).
    pub height_on: f32,
    /// ... and below this speed (length unit per second).
    pub speed_on: f32,
    /// It lasts while the height stays below this ...
    pub height_off: f32,
    /// ... and the speed below this.
    pub speed_off: f32,
    /// Shorter contacts (frames) are dropped.
    pub min_frames: usize,
}

/// A contact of one joint: frames `start..=end`, and where the joint is held.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Window {
    /// First frame in contact.
    pub start: usize,
    /// Last frame in contact (inclusive).
    pub end: usize,
    /// Model-space position the joint is pinned at.
    pub pin: Vec3,
}

impl Window {
    pub fn contains(&self, frame: usize) -> bool {
        (self.start..=self.end).contains(&frame)
    }
}

/// Speed per frame (length unit per second): central differences inside, one-sided at the
/// ends; 0 for a single frame.
pub(crate) fn speeds(positions: &[Vec3], times: &[f32]) -> Vec<f32> {
    let n = positions.len();
    (0..n)
        .map(|f| {
            let (a, b) = (f.saturating_sub(1), (f + 1).min(n.saturating_sub(1)));
            let dt = times[b] - times[a];
            if b > a && dt > 0.0 {
                (positions[b] - positions[a]).length() / dt
            } else {
                0.0
            }
        })
        .collect()
}

/// The ground under a joint at each frame: its lowest height within `window` frames either
/// side.
pub(crate) fn local_ground(heights: &[f32], window: usize) -> Vec<f32> {
    let n = heights.len();
    (0..n)
        .map(|f| {
            let lo = f.saturating_sub(window);
            let hi = (f + window + 1).min(n);
            heights[lo..hi]
                .iter()
                .copied()
                .fold(f32::INFINITY, f32::min)
        })
        .collect()
}

/// Contact frame ranges (inclusive) of one joint, with hysteresis: a contact starts on a
/// frame whose height above `ground` (per frame) and speed are both under the `_on` thresholds, and
/// lasts while both stay under the `_off` ones. Contacts shorter than `min_frames` are
/// dropped.
pub(crate) fn detect(
    heights: &[f32],
    speeds: &[f32],
    ground: &[f32],
    t: &Thresholds,
) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut open: Option<usize> = None;
    for (f, ((&h, &v), &g)) in heights.iter().zip(speeds).zip(ground).enumerate() {
        let h = h - g;
        match open {
            None if h <= t.height_on && v <= t.speed_on => open = Some(f),
            Some(start) if !(h <= t.height_off && v <= t.speed_off) => {
                out.push((start, f - 1));
                open = None;
            }
            _ => {}
        }
    }
    if let Some(start) = open {
        out.push((start, heights.len() - 1));
    }
    out.retain(|&(s, e)| e + 1 - s >= t.min_frames.max(1));
    out
}

/// How a contact's pin is chosen.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PinAt {
    /// The joint's mean position over the contact: the smallest largest correction (the
    /// source's slide is split between the contact's start and end).
    #[default]
    Mean,
    /// The joint's position at the contact's first frame (touch-down).
    First,
}

/// Pins for the contacts of one foot's ankle and toe, in time order. A contact that starts
/// while the other joint is already pinned is pinned rigidly to it (`pin_other +
/// (p_self - p_other)` at its first frame), so that a foot with both joints down can hold
/// both exactly; otherwise [`PinAt`] decides.
pub(crate) fn pin_windows(
    ankle: &[(usize, usize)],
    toe: &[(usize, usize)],
    ankle_positions: &[Vec3],
    toe_positions: Option<&[Vec3]>,
    at: PinAt,
) -> (Vec<Window>, Vec<Window>) {
    let make = |ranges: &[(usize, usize)]| -> Vec<Window> {
        ranges
            .iter()
            .map(|&(start, end)| Window {
                start,
                end,
                pin: Vec3::ZERO,
            })
            .collect()
    };
    let mut sides = [make(ankle), make(toe)];
    let positions = [Some(ankle_positions), toe_positions];
    // Visit every window by start frame (ankle first on ties).
    let mut order: Vec<(usize, usize, usize)> = sides
        .iter()
        .enumerate()
        .flat_map(|(s, ws)| ws.iter().enumerate().map(move |(i, w)| (w.start, s, i)))
        .collect();
    order.sort_unstable();
    let mut done = [vec![false; sides[0].len()], vec![false; sides[1].len()]];
    for (start, s, i) in order {
        let Some(own) = positions[s] else { continue };
        let w = sides[s][i];
        let other = 1 - s;
        let anchor = positions[other].and_then(|p_other| {
            sides[other]
                .iter()
                .zip(&done[other])
                .find(|(o, d)| **d && o.contains(start))
                .map(|(o, _)| o.pin + (own[start] - p_other[start]))
        });
        let pin = anchor.unwrap_or_else(|| match at {
            PinAt::First => own[w.start],
            PinAt::Mean => {
                let sum: Vec3 = own[w.start..=w.end].iter().copied().sum();
                sum / (w.end + 1 - w.start) as f32
            }
        });
        sides[s][i].pin = pin;
        done[s][i] = true;
    }
    let [a, t] = sides;
    (a, t)
}

/// `3x² - 2x³`: 0 at 0, 1 at 1, flat at both ends.
fn smoothstep(x: f32) -> f32 {
    let x = x.clamp(0.0, 1.0);
    x * x * (3.0 - 2.0 * x)
}

/// Where one joint should be at `frame`: `(weight, goal, inside)`. Inside a contact: weight
/// 1 at its pin. Within `blend` frames before a contact's start or after its end the weight
/// ramps (smoothstep of the distance) and the goal is the weighted mean of the near pins;
/// elsewhere `None`.
pub(crate) fn goal_at(windows: &[Window], frame: usize, blend: usize) -> Option<(f32, Vec3, bool)> {
    if let Some(w) = windows.iter().find(|w| w.contains(frame)) {
        return Some((1.0, w.pin, true));
    }
    let mut total = 0.0f32;
    let mut sum = Vec3::ZERO;
    for w in windows {
        let gap = if frame < w.start {
            w.start - frame
        } else {
            frame - w.end
        };
        if gap <= blend {
            let weight = smoothstep(1.0 - gap as f32 / (blend + 1) as f32);
            total += weight;
            sum += weight * w.pin;
        }
    }
    (total > 0.0).then(|| (total.min(1.0), sum / total, false))
}

/// How far a joint moves during its contacts: per contact frame, the distance from where it
/// was at the contact's first frame. Returns `(largest, sum, frames)`.
pub(crate) fn slide(windows: &[Window], positions: &[Vec3]) -> (f32, f64, usize) {
    let mut largest = 0.0f32;
    let mut sum = 0.0f64;
    let mut frames = 0usize;
    for w in windows {
        let p0 = positions[w.start];
        for p in &positions[w.start..=w.end] {
            let d = (*p - p0).length();
            largest = largest.max(d);
            sum += f64::from(d);
            frames += 1;
        }
    }
    (largest, sum, frames)
}

#[cfg(test)]
mod tests {
    use super::*;

    const T: Thresholds = Thresholds {
        height_on: 1.0,
        speed_on: 1.0,
        height_off: 2.0,
        speed_off: 2.0,
        min_frames: 3,
    };

    #[test]
    fn hysteresis_and_minimum_length() {
        // Enters at frame 1 (both under 1), stays through 1.5 (under the off thresholds),
        // leaves at frame 5 (speed 3). The 2-frame contact at the end is dropped.
        let h = [5.0, 0.5, 1.5, 1.5, 0.5, 0.5, 5.0, 0.5, 0.5];
        let v = [0.0, 0.5, 1.5, 0.5, 0.5, 3.0, 0.0, 0.0, 0.0];
        assert_eq!(detect(&h, &v, &[0.0; 9], &T), vec![(1, 4)]);
        // A frame over the off threshold ends a contact; the ground shifts heights.
        let h2 = [10.5, 10.5, 10.5, 12.5, 10.5, 10.5, 10.5];
        assert_eq!(detect(&h2, &[0.0; 7], &[10.0; 7], &T), vec![(0, 2), (4, 6)]);
    }

    #[test]
    fn pins_of_overlapping_contacts_are_rigid() {
        // The ankle slides +x by 1 per frame; the toe sits 2 ahead of it.
        let ankle: Vec<Vec3> = (0..10).map(|f| Vec3::new(f as f32, 0.0, 0.0)).collect();
        let toe: Vec<Vec3> = ankle
            .iter()
            .map(|p| *p + Vec3::new(2.0, 0.0, 0.0))
            .collect();
        let (a, t) = pin_windows(&[(0, 4)], &[(2, 8)], &ankle, Some(&toe), PinAt::Mean);
        assert_eq!(a[0].pin, Vec3::new(2.0, 0.0, 0.0));
        // The toe contact starts inside the ankle's: 2 ahead of the ankle's pin.
        assert_eq!(t[0].pin, Vec3::new(4.0, 0.0, 0.0));
        let (a, _) = pin_windows(&[(3, 4)], &[], &ankle, None, PinAt::First);
        assert_eq!(a[0].pin, Vec3::new(3.0, 0.0, 0.0));
    }

    #[test]
    fn goals_ramp_in_and_out() {
        let w = [Window {
            start: 5,
            end: 6,
            pin: Vec3::X,
        }];
        assert_eq!(goal_at(&w, 5, 2), Some((1.0, Vec3::X, true)));
        assert_eq!(goal_at(&w, 2, 2), None);
        let (before, _, inside) = goal_at(&w, 4, 2).unwrap();
        let (far, _, _) = goal_at(&w, 3, 2).unwrap();
        assert!(!inside && 0.0 < far && far < before && before < 1.0);
        assert_eq!(goal_at(&w, 7, 2).unwrap().0, before);
        assert_eq!(goal_at(&w, 9, 2), None);
    }

    #[test]
    fn slide_is_distance_from_touch_down() {
        let p: Vec<Vec3> = (0..5).map(|f| Vec3::new(f as f32, 0.0, 0.0)).collect();
        let w = [Window {
            start: 1,
            end: 3,
            pin: Vec3::ZERO,
        }];
        assert_eq!(slide(&w, &p), (2.0, 3.0, 3));
    }
}
