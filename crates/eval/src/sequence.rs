//! Sequencing: concatenation with crossfades, seamless loops, trimming.
