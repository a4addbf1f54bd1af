//! A generated bone mesh: one small skinned shape per bone, so skeleton-only inputs show their motion.
