//! obj importer (being written).
