"""The linear motion out of the plane of a planar state (docs/theory/out_of_plane.md)."""
