"""The motor/encoder hardware bridge node and its safety layer."""
