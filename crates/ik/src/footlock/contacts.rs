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

/// The farthest a contact's pin is moved into the leg's reach, as a fraction of the reach
/// (5%: 4 to 5 cm on an adult, several times a planted foot's slide in the corpus).
const MAX_PIN_MOVE: f32 = 0.05;

/// Where one joint can be held: per frame, the hip's position and the largest distance
/// from it at which the soft, stretched leg still puts the joint exactly on its pin.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Reach<'a> {
    /// The hip per frame, model space.
    pub hips: &'a [Vec3],
    /// The largest hip-to-joint distance held exactly (length unit).
    pub radius: f32,
}

impl Reach<'_> {
    fn reaches(&self, pin: Vec3, frame: usize) -> bool {
        (pin - self.hips[frame]).length() <= self.radius
    }

    /// The point nearest `pin` within reach at every frame of `start..=end`, as near as
    /// cyclic projections onto the balls around the hip find it (von Neumann's alternating
    /// projections; a few sweeps suffice for the short arcs a hip draws in one contact).
    fn project(&self, mut pin: Vec3, start: usize, end: usize) -> Vec3 {
        let inner = self.radius * (1.0 - 1e-4);
        for _ in 0..64 {
            let mut moved = false;
            for hip in &self.hips[start..=end] {
                let d = pin - *hip;
                if d.length() > inner {
                    pin = *hip + d.normalize_or_zero() * inner;
                    moved = true;
                }
            }
            if !moved {
                break;
            }
        }
        pin
    }

    /// `w` with its pin moved into reach over the whole window when some point is (a
    /// small move: about the source's slide); otherwise the ends the pin is out of reach
    /// at are left out first (the foot landing or lifting), and the pin is moved into reach
    /// over what is left. A pin is moved at most [`MAX_PIN_MOVE`] of the reach: farther
    /// than that the foot is not planted there.
    fn fit(&self, w: Window) -> Vec<Window> {
        let moved = |run: Window| {
            let pin = self.project(run.pin, run.start, run.end);
            ((pin - run.pin).length() <= MAX_PIN_MOVE * self.radius)
                .then_some(Window { pin, ..run })
        };
        if let Some(whole) = moved(w) {
            if (w.start..=w.end).all(|f| self.reaches(whole.pin, f)) {
                return vec![whole];
            }
        }
        self.trim(w)
            .into_iter()
            .filter_map(moved)
            .flat_map(|run| self.trim(run))
            .collect()
    }

    /// The runs of at least two frames of `w` where its pin is in reach (usually one: the
    /// window without the frames at its ends where the foot is landing or lifting).
    fn trim(&self, w: Window) -> Vec<Window> {
        let mut out = Vec::new();
        let mut run: Option<usize> = None;
        for f in w.start..=w.end + 1 {
            let inside = f <= w.end && self.reaches(w.pin, f);
            match (run, inside) {
                (None, true) => run = Some(f),
                (Some(start), false) => {
                    if f - 1 > start {
                        out.push(Window {
                            start,
                            end: f - 1,
                            pin: w.pin,
                        });
                    }
                    run = None;
                }
                _ => {}
            }
        }
        out
    }
}

/// Pins for the contacts of one foot's ankle and toe, in time order. A contact that starts
/// while the other joint is already pinned is pinned rigidly to it (`pin_other +
/// (p_self - p_other)` at its first frame), so that a foot with both joints down can hold
/// both exactly; otherwise [`PinAt`] decides, and the pin is moved to the nearest point
/// the leg reaches over the whole contact. The frames where its pin is still out of reach
/// (at a contact's ends, where the foot lands or lifts) are left out of it, splitting it
/// if need be (`reach`: the ankle's, then the toe's).
pub(crate) fn pin_windows(
    ankle: &[(usize, usize)],
    toe: &[(usize, usize)],
    ankle_positions: &[Vec3],
    toe_positions: Option<&[Vec3]>,
    at: PinAt,
    reach: [Reach<'_>; 2],
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
    let sides = [make(ankle), make(toe)];
    let positions = [Some(ankle_positions), toe_positions];
    // Visit every window by start frame (ankle first on ties).
    let mut order: Vec<(usize, usize, usize)> = sides
        .iter()
        .enumerate()
        .flat_map(|(s, ws)| ws.iter().enumerate().map(move |(i, w)| (w.start, s, i)))
        .collect();
    order.sort_unstable();
    let mut done: [Vec<Window>; 2] = [Vec::new(), Vec::new()];
    for (start, s, i) in order {
        let Some(own) = positions[s] else { continue };
        let w = sides[s][i];
        let other = 1 - s;
        let anchor = positions[other].and_then(|p_other| {
            done[other]
                .iter()
                .find(|o| o.contains(start))
                .map(|o| o.pin + (own[start] - p_other[start]))
        });
        let Some(pin) = anchor else {
            let pin = match at {
                PinAt::First => own[w.start],
                PinAt::Mean => {
                    let sum: Vec3 = own[w.start..=w.end].iter().copied().sum();
                    sum / (w.end + 1 - w.start) as f32
                }
            };
            done[s].extend(reach[s].fit(Window { pin, ..w }));
            continue;
        };
        done[s].extend(reach[s].trim(Window { pin, ..w }));
    }
    let [mut a, mut t] = done;
    a.sort_by_key(|w| w.start);
    t.sort_by_key(|w| w.start);
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
        let hips = [Vec3::ZERO; 10];
        let far = Reach {
            hips: &hips,
            radius: 100.0,
        };
        let (a, t) = pin_windows(
            &[(0, 4)],
            &[(2, 8)],
            &ankle,
            Some(&toe),
            PinAt::Mean,
            [far; 2],
        );
        assert_eq!(a[0].pin, Vec3::new(2.0, 0.0, 0.0));
        // The toe contact starts inside the ankle's: 2 ahead of the ankle's pin.
        assert_eq!(t[0].pin, Vec3::new(4.0, 0.0, 0.0));
        let (a, _) = pin_windows(&[(3, 4)], &[], &ankle, None, PinAt::First, [far; 2]);
        assert_eq!(a[0].pin, Vec3::new(3.0, 0.0, 0.0));
    }

    #[test]
    fn pins_move_into_reach_and_unreachable_ends_are_trimmed() {
        // The hip walks +x by 1 a frame, 2 above the ground; the ankle stays at 0 (reach
        // 2.5: reachable from the hip at x in [-1.5, 1.5]).
        let hips: Vec<Vec3> = (0..10)
            .map(|f| Vec3::new(f as f32 - 4.0, 2.0, 0.0))
            .collect();
        let ankle = vec![Vec3::ZERO; 10];
        let reach = Reach {
            hips: &hips,
            radius: 2.5,
        };
        // Frames 3..=5 (hip at -1, 0, 1): the mean pin is reachable throughout.
        let (a, _) = pin_windows(&[(3, 5)], &[], &ankle, None, PinAt::Mean, [reach; 2]);
        assert_eq!((a[0].start, a[0].end, a[0].pin), (3, 5, Vec3::ZERO));
        // Frames 0..=9: the hip passes from -4 to 5; the frames where the pin is out of
        // reach are left out.
        let (a, _) = pin_windows(&[(0, 9)], &[], &ankle, None, PinAt::Mean, [reach; 2]);
        assert_eq!((a[0].start, a[0].end, a[0].pin), (3, 5, Vec3::ZERO));
        // A pin just out of reach moves into it: the ankle 2.6 below a standing hip.
        let low = vec![Vec3::new(0.0, -0.6, 0.0); 10];
        let still = [Vec3::new(0.0, 2.0, 0.0); 10];
        let reach_still = Reach {
            hips: &still,
            radius: 2.5,
        };
        let (a, _) = pin_windows(&[(3, 5)], &[], &low, None, PinAt::Mean, [reach_still; 2]);
        assert_eq!((a[0].start, a[0].end), (3, 5));
        assert!((a[0].pin - still[0]).length() <= 2.5);
        // A window with no two frames in reach is dropped.
        let near = Reach {
            hips: &hips,
            radius: 1.0,
        };
        let (a, _) = pin_windows(&[(0, 9)], &[], &ankle, None, PinAt::Mean, [near; 2]);
        assert!(a.is_empty(), "{a:?}");
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
