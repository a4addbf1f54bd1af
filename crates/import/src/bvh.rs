//! BioVision Hierarchy (BVH) motion capture.
