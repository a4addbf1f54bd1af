//! The fixed-rate frame grid every resampling command samples a clip on.

use crate::EvalError;

/// The most frames a [`FrameGrid`] may hold: one million, 9.3 hours at 30 fps, 69 minutes
/// at 240 fps. Far above any real clip, and small enough that the times (4 MB) and the
/// per-frame work are bounded; a rate like `--fps 1e9` fails at once instead of allocating
/// until the process dies.
pub const MAX_FRAMES: usize = 1_000_000;

/// Frame times on a fixed-rate grid: `start, start + 1/fps, ...` while before `end`, then
/// `end` itself (included even when off the grid), in seconds, computed in `f32` as
/// `start + k as f32 / fps`. A time within a millionth of a frame of `end` is `end`.
///
/// ```
/// use rigport_eval::sample::FrameGrid;
///
/// let grid = FrameGrid::new(0.0, 1.05, 10.0)?;
/// assert_eq!(grid.len(), 12); // 0, 0.1, ..., 1.0, then the end 1.05
/// assert_eq!(grid.times().last(), Some(&1.05));
/// let err = FrameGrid::new(0.0, 2.5, 1e9).unwrap_err();
/// assert_eq!(err.to_string(), "frame rate 1000000000 fps over 2.5 s needs 2500000001 frames; the limit is 1000000");
/// # Ok::<(), rigport_eval::EvalError>(())
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct FrameGrid {
    times: Vec<f32>,
    fps: f32,
}

impl FrameGrid {
    /// The grid from `start` to `end` (seconds) at `fps` frames per second, with at most
    /// [`MAX_FRAMES`] frames.
    ///
    /// # Errors
    /// As [`FrameGrid::with_limit`].
    pub fn new(start: f32, end: f32, fps: f32) -> Result<Self, EvalError> {
        Self::with_limit(start, end, fps, MAX_FRAMES)
    }

    /// The grid from `start` to `end` at `fps`, with at most `max_frames` frames.
    ///
    /// # Errors
    /// [`EvalError::FrameRate`] for a non-finite or non-positive `fps` or a non-finite
    /// `start` or `end`; [`EvalError::TooManyFrames`] (before allocating) when the grid
    /// would hold more than `max_frames` frames.
    pub fn with_limit(
        start: f32,
        end: f32,
        fps: f32,
        max_frames: usize,
    ) -> Result<Self, EvalError> {
        if !(fps.is_finite() && fps > 0.0 && start.is_finite() && end.is_finite()) {
            return Err(EvalError::FrameRate { fps });
        }
        // An upper bound of the loop below, in f64 so a huge product does not wrap.
        let steps = (f64::from(end) - f64::from(start)).max(0.0) * f64::from(fps);
        let frames = steps.ceil() + 1.0;
        if frames > max_frames as f64 {
            return Err(EvalError::TooManyFrames {
                fps,
                duration: end - start,
                frames: frames as u64,
                limit: max_frames,
            });
        }
        let mut times = Vec::with_capacity(frames as usize);
        let mut k = 0u32;
        // Bounded: at most (end - start) * fps steps (plus one for rounding).
        while start + k as f32 / fps < end - 1e-6 / fps {
            times.push(start + k as f32 / fps);
            k += 1;
        }
        times.push(end);
        Ok(Self { times, fps })
    }

    /// The frame times, seconds, strictly increasing when `start < end`.
    pub fn times(&self) -> &[f32] {
        &self.times
    }

    /// The times, owned.
    pub fn into_times(self) -> Vec<f32> {
        self.times
    }

    /// Frames per second.
    pub fn fps(&self) -> f32 {
        self.fps
    }

    /// How many frames (at least 1).
    pub fn len(&self) -> usize {
        self.times.len()
    }

    /// Never: a grid holds at least its end.
    pub fn is_empty(&self) -> bool {
        self.times.is_empty()
    }
}
