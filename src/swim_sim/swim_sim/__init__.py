"""The dynamics simulator node with disturbances (issue 5)."""
