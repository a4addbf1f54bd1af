//! Asset -> USD text (.usda) with UsdSkel.
