//! How a writer stores key values, for the reducer to measure what a reader gets.

/// How a writer stores key values, as functions from a value to what a reader gets back.
#[derive(Clone, Copy, Debug)]
pub struct Codec {
    /// A LINEAR or STEP rotation key (xyzw, any length) as read back.
    pub rotation: fn([f32; 4]) -> [f32; 4],
    /// A LINEAR or STEP translation or scale key as read back (`None`: exactly).
    pub vector: Option<fn([f32; 3]) -> [f32; 3]>,
}

impl Codec {
    /// Rotations as 16-bit normalized integers (core glTF), other values exact.
    pub const I16: Codec = Codec {
        rotation: rigport_model::quantize::rotation_as_i16,
        vector: None,
    };
}
