//! Bounding volume hierarchy (placeholder until the builder lands).
