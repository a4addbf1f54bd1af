//! End-to-end tests: skinning.
