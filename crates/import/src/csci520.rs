//! USC CSCI 520 skinning/IK folders (being written).
