"""The geometry interface shared by SDF and mesh scenes, and (later) BVH build and traversal."""
