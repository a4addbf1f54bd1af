//! COLLADA importer tests.
