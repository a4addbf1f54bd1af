//! End-to-end tests: usd.
