//! End-to-end tests: pictures.
