//! gltf importer (being written).
