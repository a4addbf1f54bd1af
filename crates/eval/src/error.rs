/// A job's inputs do not fit together. Found by `validate()`, before any work.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum EvalError {
    /// Two buffers that must have the same length do not.
    #[error("{what}: expected {expected} elements, found {found}")]
    Length {
        /// Which buffer.
        what: &'static str,
        /// The length the other inputs require.
        expected: usize,
        /// Its length.
        found: usize,
    },
    /// An index points outside its buffer, or a parent comes after its child.
    #[error("{what}: index {index} is out of range or out of order")]
    Index {
        /// Which index list.
        what: &'static str,
        /// The bad index.
        index: usize,
    },
    /// A pose names a joint the skeleton does not have.
    #[error("no joint named {0:?}")]
    UnknownJoint(String),
    /// A frame rate that is not a positive finite number (or a grid with a non-finite end).
    #[error("frame rate {fps}: expected a positive number of frames per second")]
    FrameRate {
        /// The rate, frames per second.
        fps: f32,
    },
    /// A frame grid would hold more than its limit ([`crate::sample::MAX_FRAMES`]).
    #[error("frame rate {fps} fps over {duration} s needs {frames} frames; the limit is {limit}")]
    TooManyFrames {
        /// The rate, frames per second.
        fps: f32,
        /// The span, seconds.
        duration: f32,
        /// Frames it would need.
        frames: u64,
        /// The limit.
        limit: usize,
    },
}
