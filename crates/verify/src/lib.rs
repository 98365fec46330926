//! Certificates for triangle meshes (in progress).
