//! End-to-end tests: motion.
