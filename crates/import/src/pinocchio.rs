//! pinocchio importer (being written).
