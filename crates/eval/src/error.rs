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
}
