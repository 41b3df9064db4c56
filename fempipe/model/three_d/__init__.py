"""The 3-D model: the pipe moving in space (docs/theory/space.md)."""
