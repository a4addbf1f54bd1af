//! Key reduction with a bound on world-space joint position error.
