//! Dual quaternion skinning, following UsdSkel so results can be compared with it.
