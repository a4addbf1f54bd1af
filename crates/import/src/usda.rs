//! USD text files (.usda) with UsdSkel skeletons, bindings and animations.
