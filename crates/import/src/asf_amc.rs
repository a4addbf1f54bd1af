//! Acclaim ASF skeletons with AMC motions (CMU motion capture).
