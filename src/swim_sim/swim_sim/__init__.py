"""The dynamics simulator node with disturbances."""
